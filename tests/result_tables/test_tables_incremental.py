"""Incremental rebuild: cells are cached per records file content, so a rebuild scores only new or
changed rollout files, and gives the same numbers as scoring everything afresh. The Dagster
evaluation_table asset builds the tables that way."""

import json

import dagster as dg
import pandas as pd
from tables_records import paper_table, records_from_counts

from b2d_pipeline.assets.evaluation import build_table
from b2d_pipeline.resources import EpisodeStore
from result_tables import OUTPUTS, summarize
from evaluation.metrics import N_BOOT, SEED
from result_tables.cells import collect_cells

CHANNELS = ("none", "equi_only", "inv_only", "inv_equi")


def write_rollouts(root, n=4) -> list:
    """Rollout files in the store's layout, one per (policy, setting, channel): 2 policies x 4 channels."""
    table = paper_table()
    table = table[(table["task"] == "Trash Disposal") & table["policy"].isin(["ACT", "DP"])]
    table = table.assign(**{c: table[c] * n // 50 for c in ("none", "equi", "inv", "full")})
    df = records_from_counts(table, n=n).assign(termination="horizon", seed=7)
    files = []
    for (policy, task, channel), g in df.groupby(["policy", "task", "channel"]):
        path = root / "evaluation" / "rollouts" / policy / task.replace(" ", "_").lower() / f"{channel}.parquet"
        path.parent.mkdir(parents=True, exist_ok=True)
        g.to_parquet(path, index=False)
        files.append(path)
    return sorted(files)


def test_only_changed_files_are_scored_again(tmp_path):
    files = write_rollouts(tmp_path)
    cache = tmp_path / "cache"
    first = collect_cells(files, n_boot=200, seed=0, cache_dir=cache)
    assert (first.computed, first.reused, len(first.cells)) == (8, 0, 8)
    again = collect_cells(files, n_boot=200, seed=0, cache_dir=cache)
    assert (again.computed, again.reused) == (0, 8)
    pd.testing.assert_frame_equal(again.cells, first.cells)
    changed = files[3]
    df = pd.read_parquet(changed)
    df["success"] = 1 - df["success"]
    df.to_parquet(changed, index=False)
    third = collect_cells(files, n_boot=200, seed=0, cache_dir=cache)
    assert (third.computed, third.reused) == (1, 7)
    fresh = collect_cells(files, n_boot=200, seed=0)           # everything scored, no cache
    pd.testing.assert_frame_equal(third.cells, fresh.cells, check_dtype=False)
    assert summarize(files, n_boot=200, cache_dir=cache)[0] == summarize(files, n_boot=200)[0]
    # other bootstrap settings are other cache entries
    assert collect_cells(files, n_boot=300, seed=0, cache_dir=cache).computed == 8


def test_a_cell_spread_over_two_files_is_scored_from_both(tmp_path):
    files = write_rollouts(tmp_path)
    whole = pd.read_parquet(files[0])
    first, second = tmp_path / "part1.parquet", tmp_path / "part2.parquet"
    whole.iloc[:2].to_parquet(first, index=False)
    whole.iloc[2:].to_parquet(second, index=False)
    split = collect_cells([first, second], n_boot=200, seed=0, cache_dir=tmp_path / "cache")
    assert len(split.cells) == 1 and split.cells.iloc[0]["N"] == len(whole)
    again = collect_cells([first, second], n_boot=200, seed=0, cache_dir=tmp_path / "cache")
    assert again.cells.iloc[0]["N"] == len(whole) and again.computed == 2   # never cached as one file's cell


def test_evaluation_table_asset_rebuilds_incrementally(tmp_path):
    files = write_rollouts(tmp_path)
    asset = build_table(["scripted_operator_rollouts"])
    # what an earlier build left in the store's cell cache (the asset's own settings)
    collect_cells(files, N_BOOT, SEED, cache_dir=tmp_path / "evaluation" / "cell_cache")
    df = pd.read_parquet(files[0])
    df.loc[0, "success"] = 1 - df.loc[0, "success"]
    df.to_parquet(files[0], index=False)       # one partition re-materialized with another result
    with dg.instance_for_test() as instance:
        result = dg.materialize([asset], resources={"store": EpisodeStore(data_root=str(tmp_path))}, instance=instance)
    assert result.success
    meta = result.asset_materializations_for_node("evaluation_table")[0].metadata
    assert (meta["cells_scored_files"].value, meta["cells_reused_files"].value) == (1, 7)
    tables = tmp_path / "evaluation" / "tables"
    assert sorted(p.name for p in tables.iterdir()) == sorted(OUTPUTS)
    summary = json.loads((tables / "summary.json").read_text())
    assert summary["metadata"]["seeds"]["episode_seed_rule"].startswith("policies.rollouts.rollout_seed")
    assert len(summary["rows"]) == 2
    table = pd.read_parquet(tmp_path / "evaluation" / "evaluation_table.parquet")
    assert len(table) == 8 and {"SR", "LSCR", "N"} <= set(table.columns)


def test_a_metric_a_file_does_not_record_stays_unavailable_whatever_it_is_scored_with(tmp_path):
    """A hand-written file without safety columns beside full records: its SafeSR is not available, not 0,
    whether the files are scored together or one by one."""
    minimal = tmp_path / "minimal.csv"
    write_rollouts(tmp_path)
    pd.read_parquet(sorted(tmp_path.rglob("*.parquet"))[0]).to_csv(minimal, index=False)
    full = tmp_path / "full.parquet"
    pd.DataFrame({"task": "t2", "embodiment": "e", "policy": "p", "channel": "none", "episode": [0, 1],
                  "success": [True, False], "safe_success": [True, False], "termination": "horizon"}).to_parquet(full)
    together = collect_cells([minimal, full], n_boot=100, seed=0).cells.set_index("task")
    alone = collect_cells([minimal, full], n_boot=100, seed=0, cache_dir=tmp_path / "c").cells.set_index("task")
    for cells in (together, alone):
        assert pd.isna(cells.loc["Trash Disposal", "SafeSR"]) and cells.loc["t2", "SafeSR"] == 0.5
