"""Per-channel evaluation rollouts of every policy (one asset per policy, from a factory) and the
benchmark's result table over all of them."""


import dagster as dg

from b2d_pipeline.assets.common import data_version
from b2d_pipeline.partitions import setting_channel_partitions
from b2d_pipeline.resources import EpisodeStore
from b2d_pipeline.ops.rollouts import build_rollout_graph
from b2d_pipeline.run_config import rollout_config
from b2d_pipeline.settings import FactorySettings
from evaluation.metrics import channel_robustness
from policies.anchors import checkpoint_anchors, episode_anchors
from policies.records import write_records
from policies.scripted_baseline import ScriptedBaseline
from result_tables import RecordsError, summarize, write_outputs
from result_tables.provenance import B2D_SEED_RULE, rollout_provenance
from sim.registry import sensor_profile

BASELINE = "scripted_operator"
CELL = ("task", "embodiment", "policy", "channel")


def build_baseline_rollouts(settings: FactorySettings):
    profile = settings.profile

    def cell(store: EpisodeStore, setting: str):
        return ScriptedBaseline(), episode_anchors(list(store.episode_dir(profile.content_hash, setting)
                                                        .glob("episode_*.hdf5")))

    # 4: one step per chunk of episodes (b2d_pipeline/ops/rollouts.py); 3: through the closed-loop runner
    return dg.graph_asset(
        build_rollout_graph(f"{BASELINE}_rollouts", rollout_config(settings), cell,
                            lambda chunk: rollout_provenance(profile.content_hash, chunk["max_steps"])),
        name=f"{BASELINE}_rollouts", ins={"upstream": dg.AssetIn("episodes", dagster_type=dg.Nothing)},
        partitions_def=setting_channel_partitions, group_name="evaluation", code_version="4",
        description="The privileged scripted baseline (reads the simulator, no images) per channel, anchored on "
                    "the recorded episodes.")


def build_policy_rollouts(settings: FactorySettings, policy: str):
    cfg = settings.policy_configs()[policy]
    profile_hash = sensor_profile(cfg.observation.sensor_profile).content_hash

    def cell(store: EpisodeStore, setting: str):
        from policies.learned import LearnedPolicy

        learned = LearnedPolicy(store.checkpoint_dir(policy, cfg.name, setting))
        return learned, checkpoint_anchors(learned.checkpoint.manifest)

    # 2: one step per chunk of episodes (b2d_pipeline/ops/rollouts.py)
    return dg.graph_asset(
        build_rollout_graph(f"{policy}_rollouts", rollout_config(settings), cell,
                            lambda chunk: rollout_provenance(profile_hash, chunk["max_steps"])),
        name=f"{policy}_rollouts", ins={"upstream": dg.AssetIn(f"{policy}_checkpoint", dagster_type=dg.Nothing)},
        partitions_def=setting_channel_partitions, group_name="evaluation", code_version="2",
        description=f"{policy.upper()} ({cfg.name}) in closed loop per channel: its views rendered online at 20 Hz, "
                    "anchored on its training scenes.")


def build_table(rollout_assets: list):
    @dg.asset(group_name="evaluation", deps=rollout_assets, code_version="3",
              automation_condition=dg.AutomationCondition.eager().without(~dg.AutomationCondition.any_deps_missing()),
              description="Stable success, LSCR and the paper's metric suite per (task, embodiment, policy, channel), "
                          "and the paper's Table 2 with its summaries in evaluation/tables/ (result_tables).")
    def evaluation_table(context: dg.AssetExecutionContext, store: EpisodeStore) -> dg.MaterializeResult:
        files = sorted((store.root / "evaluation" / "rollouts").glob("*/*/*.parquet"))
        if not files:
            raise dg.Failure("no rollouts found; materialize the *_rollouts assets first")
        try:   # cells cached per rollout file hash: only new or changed partitions are scored again
            summary, scored = summarize(files, given={"episode_seed_rule": B2D_SEED_RULE},
                                        cache_dir=store.root / "evaluation" / "cell_cache")
        except RecordsError as exc:
            raise dg.Failure(description=str(exc)) from exc
        tables = write_outputs(summary, store.root / "evaluation" / "tables")
        cells = scored.cells
        robustness = channel_robustness(cells, by=("task", "embodiment", "policy"))
        out = store.evaluation_table_path()
        write_records(cells, out)
        write_records(robustness, out.with_name("channel_robustness.parquet"))
        described = store.describe([out, out.with_name("channel_robustness.parquet"), tables / "summary.json"])
        preview = cells[[*CELL, "SR", "LSCR", "N"]] if {"SR", "LSCR", "N"} <= set(cells.columns) else cells
        return dg.MaterializeResult(
            metadata={"cells": len(cells), "table": dg.MetadataValue.md(preview.to_markdown(index=False)),
                      "path": dg.MetadataValue.path(str(out)), "tables": dg.MetadataValue.path(str(tables)),
                      "cells_reused_files": scored.reused, "cells_scored_files": scored.computed},
            data_version=data_version(described))

    return evaluation_table
