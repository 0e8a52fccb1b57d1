"""Per-channel evaluation rollouts and the benchmark's result table."""


import json

import dagster as dg
import pandas as pd

from b2d_pipeline.assets.common import data_version
from b2d_pipeline.partitions import setting_channel_partitions
from b2d_pipeline.resources import EpisodeStore
from b2d_pipeline.settings import FactorySettings
from episodes.atomic import atomic_path
from episodes.reader import EpisodeReader
from evaluation.metrics import cell_metrics, channel_robustness
from sim.registry import parse_setting_key
from sim.scene.sample import SceneSample
from teleop.rollouts import run_rollouts

POLICY = "scripted_operator"
CELL = ("task", "embodiment", "policy", "channel")


def _write_parquet(df: pd.DataFrame, path) -> None:
    with atomic_path(path) as tmp:
        df.to_parquet(tmp, index=False)


def build(settings: FactorySettings):
    profile = settings.profile

    @dg.asset(partitions_def=setting_channel_partitions, group_name="evaluation", deps=["episodes"],
              code_version="2", description="Scripted-operator rollouts per channel, anchored on the recorded episodes.")
    def channel_rollouts(context: dg.AssetExecutionContext, store: EpisodeStore) -> dg.MaterializeResult:
        keys = context.partition_key.keys_by_dimension
        setting = parse_setting_key(keys["setting"])
        anchors = []
        for path in sorted(store.episode_dir(profile.content_hash, keys["setting"]).glob("episode_*.hdf5")):
            with EpisodeReader(path) as r:
                anchors.append((path.stem, SceneSample.from_json(json.dumps(r.meta("scene")))))
        rows = run_rollouts(setting.task, setting.embodiment, keys["channel"], anchors,
                            settings.eval_episodes, max_steps=settings.max_steps, policy=POLICY)
        df = pd.DataFrame(rows)
        for col in df.columns:   # nested lists/dicts -> JSON text so parquet stays flat
            if df[col].map(lambda v: isinstance(v, (list, dict))).any():
                df[col] = df[col].map(json.dumps)
        out = store.rollout_path(POLICY, keys["setting"], keys["channel"])
        _write_parquet(df, out)
        described = store.describe([out])
        return dg.MaterializeResult(
            metadata={"rollouts": len(df), "successes": int(df["success"].sum()), "anchors": len(anchors),
                      "file": dg.MetadataValue.path(str(out))},
            data_version=data_version(described))

    @dg.asset(group_name="evaluation", deps=[channel_rollouts], code_version="1",
              automation_condition=dg.AutomationCondition.eager().without(~dg.AutomationCondition.any_deps_missing()),
              description="Stable success, LSCR and the paper's metric suite per (task, embodiment, policy, channel).")
    def evaluation_table(context: dg.AssetExecutionContext, store: EpisodeStore) -> dg.MaterializeResult:
        files = sorted((store.root / "evaluation" / "rollouts").glob("*/*/*.parquet"))
        if not files:
            raise dg.Failure("no channel rollouts found; materialize channel_rollouts first")
        rollouts = pd.concat([pd.read_parquet(f) for f in files], ignore_index=True)
        for col in ("lscr", "cscr", "t_stable"):
            rollouts[col] = pd.to_numeric(rollouts.get(col), errors="coerce")
        cells = cell_metrics(rollouts.fillna({"hard_violation": False, "drop": False, "high_speed": False,
                                              "safe_success": False, "isr_ever": False, "success_final": False,
                                              "violation_steps": 0, "n_steps": 0}), by=CELL)
        robustness = channel_robustness(cells, by=("task", "embodiment", "policy"))
        out = store.evaluation_table_path()
        _write_parquet(cells, out)
        _write_parquet(robustness, out.with_name("channel_robustness.parquet"))
        described = store.describe([out, out.with_name("channel_robustness.parquet")])
        preview = cells[[*CELL, "SR", "LSCR", "N"]] if {"SR", "LSCR", "N"} <= set(cells.columns) else cells
        return dg.MaterializeResult(
            metadata={"cells": len(cells), "table": dg.MetadataValue.md(preview.to_markdown(index=False)),
                      "path": dg.MetadataValue.path(str(out))},
            data_version=data_version(described))

    return channel_rollouts, evaluation_table
