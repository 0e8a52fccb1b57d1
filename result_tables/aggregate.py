"""From cells to the paper's Table 2 numbers: one row per (task, embodiment, policy), the task-macro
row per policy and the per-policy summaries (paper section "Main Results" / "Generalization
Patterns"). Bootstrap intervals for SR only, as in the paper (95 %, 10,000 resamples, seed 0).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from evaluation.metrics import CHANNELS, LEVEL
from result_tables.schema import LABELS

TIE = 1e-12


def _num(v):
    """A JSON-ready number: NaN/None -> None, numpy scalars -> Python."""
    if v is None:
        return None
    v = v.item() if isinstance(v, np.generic) else v
    return None if isinstance(v, float) and np.isnan(v) else v


def _mean(values) -> float | None:
    vals = [v for v in values if v is not None]
    return float(np.mean(vals)) if vals else None


def stratified_sr_ci(n: np.ndarray, k: np.ndarray, weights: np.ndarray, n_boot: int, seed: int,
                     level: float = LEVEL) -> tuple[float | None, float | None]:
    """Percentile-bootstrap interval of a weighted mean of cell SRs, resampling each cell's episodes
    with replacement (stratified by cell). A resampled success count of a cell with k of n successes is
    Binomial(n, k/n), so only counts are needed; the same seed gives the same interval."""
    if len(n) == 0:
        return None, None
    rng = np.random.default_rng(seed)
    draws = rng.binomial(n.astype(np.int64)[None, :], (k / n)[None, :], size=(n_boot, len(n))) / n[None, :]
    stats = draws @ weights
    tail = 100.0 * (1.0 - level) / 2.0
    lo, hi = np.percentile(stats, [tail, 100.0 - tail])
    return float(lo), float(hi)


def _order(values) -> list:
    return sorted(set(values), key=lambda v: (str(v).lower(), str(v)))


def table_rows(cells: pd.DataFrame) -> list[dict]:
    """One row per (task, embodiment, policy): count, N, SR (with its interval) and LSCR per channel,
    then the four-channel mean SR and LSCR (means over the channels present)."""
    rows = []
    for (task, emb, policy), g in cells.groupby(["task", "embodiment", "policy"], sort=False):
        per = {c["channel"]: c for c in g.to_dict("records")}
        channels = {}
        for ch in CHANNELS:
            c = per.get(ch)
            channels[ch] = None if c is None else {
                "n_success": int(c["n_success"]), "N": int(c["N"]), "SR": _num(c["SR"]),
                "SR_ci": [_num(c["SR_ci_low"]), _num(c["SR_ci_high"])], "LSCR": _num(c["LSCR"]),
                "n_errors": int(c["n_errors"])}
        present = [v for v in channels.values() if v is not None]
        rows.append({"task": task, "embodiment": emb, "policy": policy, "channels": channels,
                     "SR": _mean([v["SR"] for v in present]), "LSCR": _mean([v["LSCR"] for v in present]),
                     "n_channels": len(present)})
    return rows


def policy_summary(policy: str, rows: list[dict], n_boot: int, seed: int, level: float = LEVEL) -> dict:
    """The macro row and the per-policy numbers the paper reports beside Table 2."""
    mine = [r for r in rows if r["policy"] == policy]
    by_channel, cells_all = {}, []
    for ch in CHANNELS:
        cells = [r["channels"][ch] for r in mine if r["channels"][ch] is not None]
        cells_all.append(cells)
        n = np.array([c["N"] for c in cells], dtype=float)
        k = np.array([c["n_success"] for c in cells], dtype=float)
        lo, hi = stratified_sr_ci(n, k, np.full(len(cells), 1.0 / max(len(cells), 1)), n_boot, seed, level)
        by_channel[ch] = {"SR": _mean([c["SR"] for c in cells]), "SR_ci": [lo, hi], "n_tasks": len(cells),
                          "successes": int(k.sum()), "episodes": int(n.sum())}
    # four-channel SR: equal-weight mean of the channels' task-mean SRs (paper: the SR column)
    used = [cells for cells in cells_all if cells]
    n = np.array([c["N"] for cells in used for c in cells], dtype=float)
    k = np.array([c["n_success"] for cells in used for c in cells], dtype=float)
    w = np.array([1.0 / (len(used) * len(cells)) for cells in used for _ in cells])
    lo, hi = stratified_sr_ci(n, k, w, n_boot, seed, level)
    sr_none, sr_full = by_channel["none"]["SR"], by_channel["inv_equi"]["SR"]
    return {
        "policy": policy, "n_tasks": len(mine), "by_channel": by_channel,
        "SR": _mean([v["SR"] for v in by_channel.values()]), "SR_ci": [lo, hi],
        "LSCR": _mean([r["LSCR"] for r in mine]),
        "full_none_ratio": sr_full / sr_none if sr_none and sr_full is not None else None,
        "full_vs_none": _compare(mine, "inv_equi", "none", ("below", "equal", "above")),
        "inv_vs_equi": _compare(mine, "inv_only", "equi_only", ("higher", "equal", "lower"), reverse=True),
    }


def _compare(rows: list[dict], a: str, b: str, names: tuple[str, str, str], reverse: bool = False) -> dict:
    """Tasks where channel a's SR is below / equal to / above channel b's (reverse: above first)."""
    below = equal = above = 0
    for r in rows:
        ca, cb = r["channels"][a], r["channels"][b]
        if ca is None or cb is None:
            continue
        d = ca["SR"] - cb["SR"]
        below, equal, above = below + (d < -TIE), equal + (abs(d) <= TIE), above + (d > TIE)
    counts = (above, equal, below) if reverse else (below, equal, above)
    return dict(zip(names, counts))


def leads(rows: list[dict], policies: list[str]) -> dict:
    """Per channel: tasks each policy leads strictly (highest SR) and tasks with a tie at the top."""
    out = {}
    for ch in CHANNELS:
        counts, ties, n_tasks = dict.fromkeys(policies, 0), 0, 0
        tasks: dict[tuple, list] = {}
        for r in rows:
            if r["channels"][ch] is not None:
                tasks.setdefault((r["task"], r["embodiment"]), []).append((r["channels"][ch]["SR"], r["policy"]))
        for entries in tasks.values():
            n_tasks += 1
            best = max(sr for sr, _ in entries)
            top = [p for sr, p in entries if sr >= best - TIE]
            if len(top) == 1:
                counts[top[0]] += 1
            else:
                ties += 1
        out[ch] = {"strict_leads": counts, "ties": ties, "n_tasks": n_tasks}
    return out


def aggregate(cells: pd.DataFrame, n_boot: int, seed: int, level: float = LEVEL) -> dict:
    """Every number of the tables, JSON-ready (NaN -> None)."""
    cells = cells.sort_values(["embodiment", "task", "policy", "channel"], kind="stable",
                              key=lambda s: s.astype(str).str.lower())
    rows = table_rows(cells)
    policies = _order(cells["policy"])
    tasks = []
    for r in rows:
        if [r["task"], r["embodiment"]] not in tasks:
            tasks.append([r["task"], r["embodiment"]])
    have = {(r["task"], r["embodiment"], r["policy"], ch) for r in rows for ch in CHANNELS if r["channels"][ch]}
    missing = [[t, e, p, ch] for t, e in tasks for p in policies for ch in CHANNELS if (t, e, p, ch) not in have]
    return {
        "channels": [{"name": ch, "label": LABELS[ch]} for ch in CHANNELS],
        "policies": policies, "tasks": tasks, "rows": rows, "missing_cells": missing,
        "policy_summaries": [policy_summary(p, rows, n_boot, seed, level) for p in policies],
        "leads": leads(rows, policies),
        "cells": [{k: _num(v) for k, v in c.items()} for c in cells.to_dict("records")],
    }
