"""Time the evaluation_table rebuild paths on paper-sized records (Table 2's counts as rollout files,
one per (policy, task, channel), 50 episodes each): everything scored at once without a cache (the
asset before result_tables), a cold cached build, a rebuild after one changed partition, and one after
none. Prints seconds and ratios against the uncached build.

    .venv/bin/python scripts/bench_result_tables.py [--policies 4] [--resamples 10000]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "result_tables"))
from tables_records import paper_table, records_from_counts  # noqa: E402

from result_tables.cells import collect_cells  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--policies", type=int, default=4)
    ap.add_argument("--resamples", type=int, default=10_000)
    args = ap.parse_args()
    table = paper_table()
    table = table[table["policy"].isin(list(dict.fromkeys(table["policy"]))[: args.policies])]
    root = Path(tempfile.mkdtemp(prefix="bench_tables_"))
    records = records_from_counts(table).assign(termination="horizon")
    files = []
    for (policy, task, channel), g in records.groupby(["policy", "task", "channel"]):
        path = root / "rollouts" / policy / task.replace(" ", "_") / f"{channel}.parquet"
        path.parent.mkdir(parents=True, exist_ok=True)
        g.to_parquet(path, index=False)
        files.append(path)
    print(f"{len(files)} rollout files, {len(records)} episodes, {args.resamples} resamples per cell")

    def timed(label, **kw):
        t0 = time.perf_counter()
        result = collect_cells(files, args.resamples, 0, **kw)
        dt = time.perf_counter() - t0
        print(f"{label:<38} {dt:8.2f} s  (scored {result.computed}, reused {result.reused})")
        return dt

    base = timed("uncached, all files scored together")
    cache = root / "cache"
    cold = timed("cached, cold (scores every file)", cache_dir=cache)
    df = pd.read_parquet(files[0])
    df.loc[0, "success"] = 1 - df.loc[0, "success"]
    df.to_parquet(files[0], index=False)
    one = timed("cached, one partition changed", cache_dir=cache)
    none = timed("cached, nothing changed", cache_dir=cache)
    print(f"ratios to uncached: cold {cold / base:.2f}x, one changed {one / base:.3f}x, none {none / base:.3f}x")


if __name__ == "__main__":
    main()
