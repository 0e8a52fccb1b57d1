"""The reproducibility metadata every output carries (paper appendix "Reproducibility Metadata"): code
version, sensor profile hash, seeds, horizon rule, N per cell, failures, dwell, the records files."""

from __future__ import annotations

import subprocess
from functools import lru_cache
from importlib import metadata
from pathlib import Path

import pandas as pd

from evaluation.metrics import LEVEL

BOOTSTRAP_METHOD = ("central percentile bootstrap; a cell resamples its episodes with replacement, a "
                    "task-macro SR resamples every task cell's episodes (stratified by cell)")


@lru_cache(maxsize=1)
def code_version() -> str:
    """The git commit of the b2d checkout (with +dirty for uncommitted tracked changes) when there is one,
    else the installed package version."""
    here = Path(__file__).resolve().parent
    try:
        commit = subprocess.run(["git", "-C", str(here), "rev-parse", "HEAD"], capture_output=True, text=True,
                                timeout=10, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(here), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=30, check=True).stdout.strip()
        return f"git:{commit}" + ("+dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        try:
            return f"b2d {metadata.version('b2d')}"
        except metadata.PackageNotFoundError:
            return "unknown"


def _values(cells: pd.DataFrame, column: str) -> list[str]:
    if column not in cells:
        return []
    return sorted({part for v in cells[column].dropna() for part in str(v).split("; ")})


def provenance(cells: pd.DataFrame, files: list[dict], n_boot: int, seed: int, given: dict | None = None,
               level: float = LEVEL) -> dict:
    """Metadata from the records (their provenance columns / file metadata) first, then ``given``
    (what the caller knows: the asset's sensor profile hash and horizon rule, CLI options)."""
    given = given or {}
    n = pd.to_numeric(cells["N"])
    seeded = cells.dropna(subset=["seed_min"]) if "seed_min" in cells else cells.iloc[:0]
    return {
        "code_version": given.get("code_version") or code_version(),
        "records_code_version": _values(cells, "code_version") or None,
        "sensor_profile_hash": _values(cells, "sensor_profile_hash") or _listed(given.get("sensor_profile_hash")),
        "horizon_rule": _values(cells, "horizon_rule") or _listed(given.get("horizon_rule")),
        "seeds": {
            "bootstrap": {"seed": seed, "resamples": n_boot, "level": level, "method": BOOTSTRAP_METHOD},
            "episode_seed_rule": given.get("episode_seed_rule"),
            "episode_seed_range": ([int(seeded["seed_min"].min()), int(seeded["seed_max"].max())]
                                   if len(seeded) else None),
            "cells_with_seeds": int(len(seeded)),
        },
        "N_per_cell": {"min": int(n.min()), "max": int(n.max()), "cells": int(len(cells)),
                       "episodes": int(n.sum())},
        "evaluation_failures": int(pd.to_numeric(cells["n_errors"]).sum()),
        "dwell_s": _values(cells, "dwell_s") or None,
        "protocol": given.get("protocol", "reach-and-stop"),
        "records": files,
    }


def _listed(value) -> list[str] | None:
    return [str(value)] if value else None


def one_line(meta: dict) -> list[str]:
    """The metadata as short 'name: value' lines for the text outputs."""
    seeds = meta["seeds"]
    n = meta["N_per_cell"]
    boot = seeds["bootstrap"]
    join = lambda v: ", ".join(v) if v else "not recorded"  # noqa: E731
    rng = seeds["episode_seed_range"]
    return [
        f"code version: {meta['code_version']}"
        + (f" (records: {join(meta['records_code_version'])})" if meta["records_code_version"] else ""),
        f"sensor profile hash: {join(meta['sensor_profile_hash'])}",
        f"horizon rule: {join(meta['horizon_rule'])}",
        f"episode seeds: {seeds['episode_seed_rule'] or 'rule not recorded'}"
        + (f"; range {rng[0]}..{rng[1]} in {seeds['cells_with_seeds']} cells" if rng else "; not recorded"),
        f"bootstrap: {boot['resamples']} resamples, seed {boot['seed']}, {100 * boot['level']:g}% central interval",
        f"N per cell: {n['min']}" + (f"..{n['max']}" if n["max"] != n["min"] else "")
        + f" ({n['cells']} cells, {n['episodes']} episodes, {meta['evaluation_failures']} ended in error)",
        f"dwell: {join(meta['dwell_s']) + ' s' if meta['dwell_s'] else 'not recorded'}; protocol: {meta['protocol']}",
        f"records: {len(meta['records'])} file(s)",
    ] + ([f"missing cells: {meta['missing_cells']} (row SR and LSCR average the channels present; "
          "summary.json lists them)"] if meta.get("missing_cells") else [])


def rollout_provenance(profile_hash: str | None, max_steps: int | None) -> dict:
    """Provenance columns b2d's rollout records carry (records contract, optional columns)."""
    from teleop.recorder import HORIZON_FACTOR

    rule = f"{HORIZON_FACTOR:g}x the task's expert horizon in control steps" + (
        f", capped at {max_steps}" if max_steps else "")
    return {"code_version": code_version(), "sensor_profile_hash": profile_hash, "horizon_rule": rule}


B2D_SEED_RULE = ("policies.rollouts.rollout_seed: task_seed(task index, 50,000,000 + channel index x 1,000,000 + "
                 "episode index)")
