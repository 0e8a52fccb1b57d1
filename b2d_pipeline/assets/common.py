"""Helpers shared by the asset modules: data versions from content hashes, failure reports."""


import hashlib
import json

import dagster as dg

# The steps that keep a core busy (simulate, render, assemble, train, roll out) share this pool; the
# instance limits it to one step per core over every run (b2d_pipeline/instance.py).
CPU_POOL = "b2d_cpu"


def data_version(described: dict, *extra: str) -> dg.DataVersion:
    blob = json.dumps({k: v["sha256"] for k, v in sorted(described.items())}, sort_keys=True) + "".join(extra)
    return dg.DataVersion(hashlib.sha256(blob.encode()).hexdigest()[:16])


def require_inputs(found: list, folder, pattern: str, upstream: str) -> list:
    """An empty partition is a failure that says why, not a green step with 0 episodes."""
    if not found:
        raise dg.Failure(description=f"no {pattern} files in {folder}: materialize {upstream} for this "
                                     "partition first")
    return found


def fail_if_errors(errors: dict[str, str], done: int) -> None:
    """Every good episode is already written; now fail the partition, naming each bad one."""
    if errors:
        lines = "\n".join(f"- {name}: {msg}" for name, msg in sorted(errors.items()))
        raise dg.Failure(description=f"{len(errors)} episode(s) failed ({done} succeeded):\n{lines}",
                         metadata={"failed": dg.MetadataValue.json(errors)})
