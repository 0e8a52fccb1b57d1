"""Benchmark metrics over episode records: per (task, policy, channel) cell, channel robustness and
task-macro means (paper appendix "Evaluation Metrics"). Undefined quantities are NaN, never 0.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Sequence

import numpy as np
import pandas as pd

from evaluation.records import EpisodeRecord

log = logging.getLogger(__name__)

CHANNELS = ("none", "equi_only", "inv_only", "inv_equi")  # paper: None, Equi., Inv., Full
SHIFTED = CHANNELS[1:]
CELL = ("task", "policy", "channel")
NEEDED = ("success", "t_stable", "lscr", "cscr", "safe_success", "hard_violation", "drop", "high_speed",
          "violation_steps", "n_steps", "isr_ever", "success_final")
N_BOOT, SEED, LEVEL = 10_000, 0, 0.95


def episode_table(records: Iterable[EpisodeRecord | dict] | pd.DataFrame) -> pd.DataFrame:
    """One row per episode from EpisodeRecords, their dicts, or an existing DataFrame."""
    if isinstance(records, pd.DataFrame):
        return records.copy()
    return pd.DataFrame([r.to_dict() if isinstance(r, EpisodeRecord) else dict(r) for r in records])


def bootstrap_ci(values: Sequence[float], n_boot: int = N_BOOT, seed: int = SEED, level: float = LEVEL,
                 chunk: int = 1000) -> tuple[float, float]:
    """Central percentile-bootstrap interval of the mean (resampling episodes with replacement)."""
    x = np.asarray(values, dtype=float)
    if x.size == 0:
        return np.nan, np.nan
    rng = np.random.default_rng(seed)
    means = np.empty(n_boot)
    for start in range(0, n_boot, chunk):
        stop = min(n_boot, start + chunk)
        means[start:stop] = x[rng.integers(0, x.size, size=(stop - start, x.size))].mean(axis=1)
    tail = 100.0 * (1.0 - level) / 2.0
    lo, hi = np.percentile(means, [tail, 100.0 - tail])
    return float(lo), float(hi)


def _mean(series: pd.Series) -> float:
    """Mean over defined values; NaN when none is defined."""
    s = pd.to_numeric(series, errors="coerce").dropna()
    return float(s.mean()) if len(s) else np.nan


def _cell(g: pd.DataFrame, n_boot: int, seed: int) -> dict:
    s = g["success"].astype(bool).to_numpy()
    lo, hi = bootstrap_ci(s.astype(float), n_boot, seed)
    t = pd.to_numeric(g.loc[s, "t_stable"], errors="coerce")
    row = {
        "N": len(g), "n_success": int(s.sum()), "SR": float(s.mean()), "SR_ci_low": lo, "SR_ci_high": hi,
        "LSCR": _mean(g["lscr"]), "t_succ": float(t.mean()) if s.any() else np.nan,
        "t_succ_note": "" if s.any() else "undefined: no successful episode",
        "SafeSR": float(g["safe_success"].astype(bool).mean()), "HVR": float(g["hard_violation"].astype(bool).mean()),
        "DropR": float(g["drop"].astype(bool).mean()), "HSR": float(g["high_speed"].astype(bool).mean()),
        "VSR_step": float(g["violation_steps"].sum() / g["n_steps"].sum()) if g["n_steps"].sum() else np.nan,
        "ISR_ever": float(g["isr_ever"].astype(bool).mean()), "SR_final": float(g["success_final"].astype(bool).mean()),
        "CSCR": _mean(g["cscr"]),
    }
    for name, column in (("TE", "te"), ("GSI", "gsi"), ("GSI_mean", "gsi_mean")):
        row[name] = _mean(g[column]) if column in g else np.nan
    row.update(_tool_and_motion(g))
    row["n_errors"] = int((g["termination"] == "error").sum()) if "termination" in g else 0
    row["mean_steps"] = float(g["n_steps"].mean())
    return row


MOTION = (("JointVel_RMS", "joint_vel_rms"), ("JointAcc_RMS", "joint_acc_rms"), ("JointJerk_RMS", "joint_jerk_rms"),
          ("JointEffort_RMS", "joint_effort_rms"))


def _tool_and_motion(g: pd.DataFrame) -> dict:
    """TSA and TSSR: means over the episodes where each is defined (with those episode counts), TSSR
    with the total attempted and successful switches; motion: means of the per-episode RMS values."""
    col = lambda name: g[name] if name in g else pd.Series(np.nan, index=g.index)  # noqa: E731
    count = lambda name: int(pd.to_numeric(col(name), errors="coerce").notna().sum())  # noqa: E731
    total = lambda name: int(pd.to_numeric(col(name), errors="coerce").fillna(0).sum())  # noqa: E731
    row = {"TSA": _mean(col("tsa")), "n_TSA": count("tsa"), "TSSR": _mean(col("tssr")), "n_TSSR": count("tssr"),
           "switch_attempts": total("tool_switch_attempts"), "switch_successes": total("tool_switch_successes")}
    row.update({name: _mean(col(column)) for name, column in MOTION})
    return row


def cell_metrics(records, by: Sequence[str] = CELL, n_boot: int = N_BOOT, seed: int = SEED) -> pd.DataFrame:
    """Core and diagnostic metrics per cell (default: task, policy, channel), one row each."""
    df = episode_table(records)
    missing = [c for c in (*by, *NEEDED) if c not in df.columns]
    if missing:
        raise ValueError(f"episode table lacks columns {missing}")
    rows = [{**dict(zip(by, key if isinstance(key, tuple) else (key,))), **_cell(g, n_boot, seed)}
            for key, g in df.groupby(list(by), sort=True)]
    return pd.DataFrame(rows)


def channel_robustness(cells_or_records, by: Sequence[str] = ("task", "policy")) -> pd.DataFrame:
    """Per group: SR and N of every channel, RR_p = SR_p / SR_none, SR_shift and RR_shift.

    RR values are NaN when SR_none is 0 or the none channel is absent (see RR_note)."""
    cells = cells_or_records
    if not (isinstance(cells, pd.DataFrame) and {"SR", "N", "channel"} <= set(cells.columns)):
        cells = cell_metrics(cells_or_records, by=(*by, "channel"))
    unknown = sorted(set(cells["channel"]) - set(CHANNELS))
    if unknown:
        raise ValueError(f"unknown channels {unknown}: expected names from {list(CHANNELS)}")
    rows = []
    for key, g in cells.groupby(list(by), sort=True):
        per = g.set_index("channel")
        row = dict(zip(by, key if isinstance(key, tuple) else (key,)))
        for p in CHANNELS:
            row[f"SR_{p}"] = float(per.at[p, "SR"]) if p in per.index else np.nan
            row[f"N_{p}"] = int(per.at[p, "N"]) if p in per.index else 0
        base = row["SR_none"]
        ok = row["N_none"] > 0 and base > 0
        for p in SHIFTED:
            row[f"RR_{p}"] = row[f"SR_{p}"] / base if ok else np.nan
        n_shift = sum(row[f"N_{p}"] for p in SHIFTED)
        row["N_shift"] = n_shift
        row["SR_shift"] = (sum(row[f"N_{p}"] * row[f"SR_{p}"] for p in SHIFTED if row[f"N_{p}"]) / n_shift
                           if n_shift else np.nan)
        row["RR_shift"] = row["SR_shift"] / base if ok and n_shift else np.nan
        row["RR_note"] = "" if ok else "undefined: SR_none is 0 or missing"
        rows.append(row)
    return pd.DataFrame(rows)


def task_macro(cells: pd.DataFrame, by: Sequence[str] = ("policy", "channel"),
               columns: Sequence[str] = ("SR", "LSCR", "SafeSR", "HVR", "DropR", "HSR")) -> pd.DataFrame:
    """Equal-weight means across tasks of per-cell metrics (benchmark-level numbers)."""
    out = cells.groupby(list(by), sort=True)[list(columns)].mean().reset_index()
    out["n_tasks"] = cells.groupby(list(by), sort=True)["task"].nunique().to_numpy()
    return out
