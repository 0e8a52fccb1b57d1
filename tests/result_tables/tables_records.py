"""Records written by hand from published per-task counts (the records contract's minimum), and the
paper's own Table 2 (tests/result_tables/paper_table2.csv: 26 settings x 4 policies, counts of 50)."""

from pathlib import Path

import pandas as pd

PAPER = Path(__file__).with_name("paper_table2.csv")
COUNTS = {"none": "none", "equi_only": "equi", "inv_only": "inv", "inv_equi": "full"}


def paper_table() -> pd.DataFrame:
    return pd.read_csv(PAPER)


def records_from_counts(table: pd.DataFrame, n: int = 50, channel_names=None) -> pd.DataFrame:
    """One row per episode: k successes then n - k failures per (task, embodiment, policy, channel);
    every episode of a row carries the row's published four-channel LSCR."""
    names = channel_names or {c: c for c in COUNTS}
    rows = []
    for r in table.itertuples(index=False):
        for ch, col in COUNTS.items():
            k = int(getattr(r, col))
            rows += [{"task": r.task, "embodiment": r.embodiment, "policy": r.policy, "channel": names[ch],
                      "episode": e, "success": int(e < k), "lscr": r.lscr_percent / 100} for e in range(n)]
    return pd.DataFrame(rows)


def cells_from_counts(table: pd.DataFrame, n: int = 50) -> pd.DataFrame:
    """The cell columns aggregate() reads, straight from counts (no episode scoring)."""
    rows = []
    for r in table.itertuples(index=False):
        for ch, col in COUNTS.items():
            k = int(getattr(r, col))
            rows.append({"task": r.task, "embodiment": r.embodiment, "policy": r.policy, "channel": ch, "N": n,
                         "n_success": k, "SR": k / n, "SR_ci_low": None, "SR_ci_high": None,
                         "LSCR": r.lscr_percent / 100, "n_errors": 0})
    return pd.DataFrame(rows)
