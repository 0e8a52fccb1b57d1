"""Benchmark metrics over episode records: per (task, policy, channel) cell, channel robustness and
task-macro means (paper appendix "Evaluation Metrics"). Undefined quantities are NaN, never 0.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Mapping, Sequence

import numpy as np
import pandas as pd

from evaluation.bootstrap_defaults import LEVEL, N_BOOT, SEED
from evaluation.records import EpisodeRecord

log = logging.getLogger(__name__)

CHANNELS = ("none", "equi_only", "inv_only", "inv_equi")  # paper: None, Equi., Inv., Full
SHIFTED = CHANNELS[1:]
CELL = ("task", "policy", "channel")
NEEDED = ("success", "t_stable", "lscr", "cscr", "safe_success", "hard_violation", "drop", "high_speed",
          "violation_steps", "n_steps", "isr_ever", "success_final")


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


def _flag(series: pd.Series) -> pd.Series:
    """Boolean flags with a missing value (None / NaN / NA, e.g. an error row without flags) as False;
    a plain ``astype(bool)`` would turn NaN into True."""
    s = series.astype(object)
    return s.where(s.notna(), False).astype(bool)


def _count(series: pd.Series) -> pd.Series:
    """Step counts with a missing value as 0 (an error row that recorded no steps executed none)."""
    return pd.to_numeric(series, errors="coerce").fillna(0.0)


def _errors(g: pd.DataFrame) -> pd.Series:
    """Episodes that ended because evaluation could not proceed (termination "error")."""
    return g["termination"].eq("error") if "termination" in g else pd.Series(False, index=g.index)


def _progress(g: pd.DataFrame, column: str, err: pd.Series) -> pd.Series:
    """Per-episode LSCR / CSCR with error episodes in the denominator: an error episode keeps a value
    it recorded (progress over the updates it executed) and counts 0 without one. A cell whose
    non-error episodes all leave the value undefined has no stages (K = 0): it stays undefined."""
    v = pd.to_numeric(g[column], errors="coerce")
    staged = v.notna().any() or bool(err.all())
    return v.mask(err & v.isna(), 0.0) if staged else v


def _te(g: pd.DataFrame, s: np.ndarray, expert_time_s: Mapping | None) -> tuple[pd.Series, str]:
    """Per-episode TE_e = t_expert / t_stable over successful episodes, and which reference was used.

    The reference is the recorded expert time of the setting's demonstrations when there is one, else
    the configured one: ``expert_time_s[(task, embodiment)]``, then a row's ``t_expert_recorded``,
    then the configured TE the evaluator wrote (``te``, from ``expert_horizon_steps`` x dt)."""
    configured = pd.to_numeric(g["te"], errors="coerce") if "te" in g else pd.Series(np.nan, index=g.index)
    recorded = (pd.to_numeric(g["t_expert_recorded"], errors="coerce") if "t_expert_recorded" in g
                else pd.Series(np.nan, index=g.index))
    if expert_time_s is not None:
        given = pd.Series([expert_time_s.get((t, e)) for t, e in zip(g["task"], g["embodiment"])],
                          index=g.index, dtype=object)
        recorded = pd.to_numeric(given, errors="coerce").fillna(recorded)
    recorded = recorded.where(recorded > 0)
    t_stable = pd.to_numeric(g["t_stable"], errors="coerce")
    from_recorded = recorded / t_stable.where(t_stable > 0)
    use = recorded.notna()
    te = from_recorded.where(use, configured).where(s)
    defined = te.notna()
    kinds = [k for k, m in (("recorded", use), ("configured", ~use)) if (defined & m).any()]
    return te, "+".join(kinds)


def _cell(g: pd.DataFrame, n_boot: int, seed: int, expert_time_s: Mapping | None = None) -> dict:
    err = _errors(g)
    s = (_flag(g["success"]) & ~err).to_numpy()  # paper: an error episode counts as unsuccessful
    lo, hi = bootstrap_ci(s.astype(float), n_boot, seed)
    t = pd.to_numeric(g.loc[s, "t_stable"], errors="coerce")
    steps, violations = _count(g["n_steps"]), _count(g["violation_steps"])
    flag = lambda name: float(_flag(g[name]).mean())  # noqa: E731
    row = {
        "N": len(g), "n_success": int(s.sum()), "SR": float(s.mean()), "SR_ci_low": lo, "SR_ci_high": hi,
        "LSCR": _mean(_progress(g, "lscr", err)), "t_succ": float(t.mean()) if s.any() else np.nan,
        "t_succ_note": "" if s.any() else "undefined: no successful episode",
        "SafeSR": float((_flag(g["safe_success"]).to_numpy() & s).mean()), "HVR": flag("hard_violation"),
        "DropR": flag("drop"), "HSR": flag("high_speed"),
        "VSR_step": float(violations.sum() / steps.sum()) if steps.sum() else np.nan,
        "ISR_ever": flag("isr_ever"), "SR_final": flag("success_final"),
        "CSCR": _mean(_progress(g, "cscr", err)),
    }
    te, source = _te(g, s, expert_time_s)
    row["TE"], row["TE_source"] = _mean(te), source
    for name, column in (("GSI", "gsi"), ("GSI_mean", "gsi_mean")):
        row[name] = _mean(g[column]) if column in g else np.nan
    row.update(_tool_and_motion(g))
    row["n_errors"] = int(err.sum())
    row["mean_steps"] = float(steps.mean())
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


def cell_metrics(records, by: Sequence[str] = CELL, n_boot: int = N_BOOT, seed: int = SEED,
                 expert_time_s: Mapping[tuple[str, str], float | None] | None = None) -> pd.DataFrame:
    """Core and diagnostic metrics per cell (default: task, policy, channel), one row each.

    Error episodes (termination "error", e.g. the bare ``{labels, success: False, termination: "error",
    error}`` rows of ``teleop/rollouts.py`` run_rollouts) stay in every denominator as failures (paper):
    S_e = 0 whatever they recorded, missing flags are False (so SafeSR <= SR), LSCR_e / CSCR_e are 0
    unless recorded, and their recorded ``n_steps`` / ``violation_steps`` count in VSR_step (missing: 0
    steps). No ``fillna`` by the caller is needed; columns of NEEDED may be absent only when every
    episode is an error episode.

    TE: ``expert_time_s`` maps (task, embodiment) to the recorded expert time in seconds of that
    setting's demonstrations (None: no recording); a row's ``t_expert_recorded`` column serves the same
    purpose. A recorded reference takes precedence over the configured one (the evaluator's ``te``,
    ``expert_horizon_steps`` x dt): TE_e = t_expert / t_stable per successful episode, in the order
    ``expert_time_s`` > ``t_expert_recorded`` > ``te``. ``TE_source`` says which was used
    ("recorded", "configured", both joined by "+", or "" when TE is undefined).
    """
    df = episode_table(records)
    missing = [c for c in by if c not in df.columns]
    if expert_time_s is not None:
        missing += [c for c in ("task", "embodiment") if c not in df.columns and c not in missing]
    if missing:
        raise ValueError(f"episode table lacks columns {missing}")
    absent = [c for c in NEEDED if c not in df.columns]
    if absent:
        if "success" in absent or not len(df) or not _errors(df).all():
            raise ValueError(f"episode table lacks columns {absent}")
        df = df.assign(**{c: np.nan for c in absent})  # only error episodes: nothing was recorded
    rows = [{**dict(zip(by, key if isinstance(key, tuple) else (key,))), **_cell(g, n_boot, seed, expert_time_s)}
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
