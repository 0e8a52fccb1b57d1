"""Read any modality of an episode for a frame range without reading the rest of the file.

Image datasets use HDF5 plugin filters (Zstd, Blosc: `episodes.writer.image_filter`); importing this
module registers them. Plain h5py needs `import hdf5plugin` first."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import hdf5plugin  # noqa: F401  (registers the image filters)
import numpy as np

from episodes import schema
from sim.errors import SpecError


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
        value = self._get(f"meta/{key}", ())
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
        return self._get(dataset, slice(start, stop))

    def static(self, dataset: str):
        value = self._get(dataset, ())
        if isinstance(value, bytes):
            return value.decode()
        if isinstance(value, np.ndarray) and value.dtype.kind == "O":
            return [v.decode() if isinstance(v, bytes) else v for v in value]
        return value

    def metrics(self) -> dict:
        try:
            return json.loads(self.static("metrics/episode"))
        except ValueError as exc:
            raise SpecError(self.path, "metrics/episode", "a JSON document", f"{type(exc).__name__}: {exc}") from None

    def _get(self, dataset: str, selection):
        """A selection of a dataset; SpecError naming the file and the dataset when it is missing or
        its data cannot be decoded (a corrupt file raised h5py's own errors before: issue 23)."""
        try:
            node = self._file[dataset]
        except (KeyError, ValueError, OSError, RuntimeError) as exc:
            raise SpecError(self.path, dataset, "a dataset", f"missing or unreadable ({type(exc).__name__})") from None
        if not isinstance(node, h5py.Dataset):
            raise SpecError(self.path, dataset, "a dataset", f"a {type(node).__name__}")
        try:
            return node[selection]
        except (OSError, ValueError, TypeError, RuntimeError) as exc:
            raise SpecError(self.path, dataset, "readable data (the file is corrupt)",
                            f"{type(exc).__name__}: {str(exc)[:120]}") from None


EPISODE_SCHEMA_FAMILY = schema.SCHEMA_VERSION.rsplit("/", 1)[0] + "/"


def open_episode(path: str | Path) -> EpisodeReader:
    """An EpisodeReader on a b2d episode; SpecError for a missing, non-HDF5 or non-episode file."""
    path = Path(path)
    if not path.is_file():
        raise SpecError(path, "<file>", "an existing HDF5 episode file")
    try:
        reader = EpisodeReader(path)
    except OSError as exc:
        raise SpecError(path, "<file>", "a readable HDF5 episode (file is truncated or not HDF5)") from exc
    # any version of the layout: what each command needs is checked node by node when it is read
    try:
        version = reader.static("meta/schema_version") if "meta/schema_version" in reader else None
    except SpecError:
        reader.close()
        raise
    except Exception as exc:        # corrupt metadata
        reader.close()
        raise SpecError(path, "meta/schema_version", "a readable b2d episode", f"{type(exc).__name__}: {exc}") from None
    if not (isinstance(version, str) and version.startswith(EPISODE_SCHEMA_FAMILY)):
        reader.close()
        raise SpecError(path, "meta/schema_version", f"'{schema.SCHEMA_VERSION}' or another "
                                                     f"'{EPISODE_SCHEMA_FAMILY}' version (a b2d episode)", version)
    if "time/frame_index" not in reader or not isinstance(reader._file.get("time/frame_index"), h5py.Dataset):
        reader.close()
        raise SpecError(path, "time/frame_index", "a dataset [T] (the episode's frames)")
    return reader
