"""`episode_manifest.json`: the per-directory index of episodes (paper HDF5 schema)."""

from __future__ import annotations

import json
from pathlib import Path

from episodes import schema
from episodes.atomic import file_sha256, write_text_atomic
from episodes.reader import EpisodeReader


def write_manifest(directory: str | Path) -> Path:
    directory = Path(directory)
    entries = []
    for path in sorted(directory.glob("episode_*.hdf5")):
        with EpisodeReader(path) as r:
            entries.append({"file": path.name, "task": r.meta("task"), "embodiment": r.meta("embodiment"),
                            "frames": r.num_frames, "success": bool(r.meta("success")),
                            "cameras": r.camera_ids, "tactile_sites": r.tactile_sites,
                            "sha256": file_sha256(path), "bytes": path.stat().st_size})
    out = directory / schema.MANIFEST_NAME
    write_text_atomic(out, json.dumps({"schema_version": schema.SCHEMA_VERSION, "episodes": entries}, indent=2))
    return out
