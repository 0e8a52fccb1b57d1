"""`episode_manifest.json`: the per-directory index of episodes (paper HDF5 schema).

Each entry records the file's sha256 and size and a digest of each dataset's stored bytes
(episodes/integrity.py) when the episode was written; `b2d validate` and the asset checks compare
against them. An entry is computed once, for a file just written (or not yet listed), and then
kept: re-hashing every file on each update would bless a file corrupted since.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import h5py

from episodes import schema
from episodes.atomic import file_sha256, write_text_atomic
from episodes.integrity import dataset_digests
from episodes.reader import EpisodeReader
from sim.errors import SpecError

log = logging.getLogger(__name__)


def manifest_entry(path: Path) -> dict:
    with EpisodeReader(path) as r:
        entry = {"file": path.name, "task": r.meta("task"), "embodiment": r.meta("embodiment"),
                 "frames": r.num_frames, "success": bool(r.meta("success")),
                 "cameras": r.camera_ids, "tactile_sites": r.tactile_sites}
    with h5py.File(path, "r") as f:
        digests = dataset_digests(f)
    return {**entry, "sha256": file_sha256(path), "bytes": path.stat().st_size, "datasets": digests}


def read_manifest(directory: str | Path) -> dict[str, dict]:
    """{file name: entry} of the directory's manifest ({} when there is none); SpecError when it is
    not a manifest."""
    path = Path(directory) / schema.MANIFEST_NAME
    if not path.exists():
        return {}
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        return {e["file"]: e for e in doc["episodes"]}
    except (ValueError, KeyError, TypeError) as exc:
        raise SpecError(path, "episodes", "a JSON manifest {schema_version, episodes: [{file, sha256, ...}]}",
                        f"{type(exc).__name__}: {exc}") from None


def write_manifest(directory: str | Path, updated: list[Path] | None = None) -> Path:
    """(Re)write the directory's manifest. Entries of `updated` files and of files not yet listed are
    computed; the others keep what they recorded. `updated=None` recomputes every entry. A file that
    cannot be read is left out (and logged), never stops the others."""
    directory = Path(directory)
    try:
        old = read_manifest(directory) if updated is not None else {}
    except SpecError as exc:
        log.warning("%s; rebuilding it", exc)
        old = {}
    fresh = {Path(p).name for p in (updated or [])}
    entries = []
    for path in sorted(directory.glob("episode_*.hdf5")):
        if path.name in old and path.name not in fresh:
            entries.append(old[path.name])
            continue
        try:
            entries.append(manifest_entry(path))
        except Exception as exc:     # a corrupt file already in the folder: the others are still listed
            log.warning("%s: left out of %s: %s", path, schema.MANIFEST_NAME, exc)
    out = directory / schema.MANIFEST_NAME
    write_text_atomic(out, json.dumps({"schema_version": schema.SCHEMA_VERSION, "episodes": entries}, indent=2))
    return out
