"""Read any modality of an episode for a frame range without reading the rest of the file."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np


class EpisodeReader:
    def __init__(self, path: str | Path):
        self.path = Path(path)
        self._file = h5py.File(self.path, "r")

    def __enter__(self) -> "EpisodeReader":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        self._file.close()

    @property
    def num_frames(self) -> int:
        return int(self._file["time/frame_index"].shape[0])

    def meta(self, key: str):
        value = self._file[f"meta/{key}"][()]
        if isinstance(value, bytes):
            value = value.decode()
            try:
                return json.loads(value)
            except json.JSONDecodeError:
                return value
        return value.item() if isinstance(value, np.generic) else value

    @property
    def camera_ids(self) -> list[str]:
        return sorted(self._file["cameras"].keys()) if "cameras" in self._file else []

    @property
    def object_ids(self) -> list[str]:
        return sorted(self._file["objects"].keys()) if "objects" in self._file else []

    def __contains__(self, dataset: str) -> bool:
        return dataset in self._file

    @property
    def tactile_sites(self) -> list[str]:
        """Tactile site names in stored order (empty when the episode has no tactile)."""
        path = "robot/tactile/site_names"
        return self.static(path) if path in self._file else []

    def read(self, dataset: str, start: int = 0, stop: int | None = None) -> np.ndarray:
        """Frames [start, stop) of one per-frame dataset, e.g. "cameras/chest/rgb"; only the
        chunks covering the range are read and decompressed."""
        return self._file[dataset][start:stop]

    def static(self, dataset: str):
        value = self._file[dataset][()]
        if isinstance(value, bytes):
            return value.decode()
        if isinstance(value, np.ndarray) and value.dtype.kind == "O":
            return [v.decode() if isinstance(v, bytes) else v for v in value]
        return value

    def metrics(self) -> dict:
        return json.loads(self.static("metrics/episode"))
