"""The project's Dagster instance settings: written as `dagster.yaml` into DAGSTER_HOME when it has none, so
that a first run prints no telemetry banner and no missing-file warning, and the run queue and the CPU pool
match the machine."""

from __future__ import annotations

import os
from pathlib import Path

import yaml

from episodes.atomic import write_text_atomic


def instance_config(cores: int | None = None) -> dict:
    cores = cores or os.cpu_count() or 1
    return {
        "telemetry": {"enabled": False},
        # the terminal shows b2d's progress lines; Dagster's own lines (every step process announces
        # itself at DEBUG before the run's logger config applies) stay in the run storage and the UI
        "python_logs": {"python_log_level": "ERROR"},
        "concurrency": {
            # one queued run per core, and across all runs at most one CPU-bound step per core (the
            # b2d_cpu pool: b2d_pipeline/assets/common.py): a backfill of many partitions keeps both
            # cores busy without running cores x cores simulations at once
            "runs": {"max_concurrent_runs": cores},
            "pools": {"default_limit": cores, "granularity": "op"},
        },
    }


def ensure_instance_yaml(dagster_home: Path) -> Path:
    """Write DAGSTER_HOME/dagster.yaml unless one exists (a user's own settings are kept)."""
    path = Path(dagster_home) / "dagster.yaml"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(path, "# written by b2d (b2d_pipeline/instance.py); edit freely, it is not overwritten\n"
                                + yaml.safe_dump(instance_config(), sort_keys=False))
    return path
