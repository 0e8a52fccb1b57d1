"""Per-episode rollout records as a flat table (the metric suite's input) and their parquet files."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from episodes.atomic import atomic_path


def records_frame(rows: list[dict]) -> pd.DataFrame:
    """Rows of `policies.rollouts.run_rollouts` -> a DataFrame; nested lists and dicts become JSON text so
    that parquet stays flat."""
    df = pd.DataFrame(rows)
    for col in df.columns:
        if df[col].map(lambda v: isinstance(v, (list, dict))).any():
            df[col] = df[col].map(lambda v: json.dumps(v) if isinstance(v, (list, dict)) else v)
    return df


def write_records(df: pd.DataFrame, path: str | Path) -> Path:
    with atomic_path(path) as tmp:
        df.to_parquet(tmp, index=False)
    return Path(path)
