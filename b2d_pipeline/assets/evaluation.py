"""Per-channel evaluation rollouts of every policy (one asset per policy, from a factory) and the
benchmark's result table over all of them."""


import dagster as dg

from b2d_pipeline.assets.common import data_version
from b2d_pipeline.partitions import setting_channel_partitions
from b2d_pipeline.resources import EpisodeStore
from b2d_pipeline.run_config import rollout_config
from b2d_pipeline.settings import FactorySettings
from evaluation.metrics import channel_robustness
from policies.anchors import checkpoint_anchors, episode_anchors
from policies.records import records_frame, write_records
from policies.rollouts import run_rollouts
from policies.scripted_baseline import ScriptedBaseline
from result_tables import RecordsError, summarize, write_outputs
from result_tables.provenance import B2D_SEED_RULE, rollout_provenance
from sim.registry import parse_setting_key, sensor_profile

BASELINE = "scripted_operator"
CELL = ("task", "embodiment", "policy", "channel")


def _rollout_result(store: EpisodeStore, rows: list[dict], policy: str, setting: str, channel: str,
                    anchors: int, provenance: dict) -> dg.MaterializeResult:
    df = records_frame(rows).assign(**provenance)   # result_tables reads these into every output
    out = write_records(df, store.rollout_path(policy, setting, channel))
    described = store.describe([out])
    errors = int((df.get("termination") == "error").sum()) if "termination" in df else 0
    return dg.MaterializeResult(
        metadata={"rollouts": len(df), "successes": int(df["success"].sum()), "errors": errors, "anchors": anchors,
                  "file": dg.MetadataValue.path(str(out))},
        data_version=data_version(described))


def build_baseline_rollouts(settings: FactorySettings):
    profile = settings.profile
    RolloutConfig = rollout_config(settings)

    # 3: rollouts through the policy interface's closed-loop runner (control steps and queries counted)
    @dg.asset(name=f"{BASELINE}_rollouts", partitions_def=setting_channel_partitions, group_name="evaluation",
              deps=["episodes"], code_version="3",
              description="The privileged scripted baseline (reads the simulator, no images) per channel, anchored "
                          "on the recorded episodes.")
    def rollouts(context: dg.AssetExecutionContext, config: RolloutConfig,
                 store: EpisodeStore) -> dg.MaterializeResult:
        keys = context.partition_key.keys_by_dimension
        setting = parse_setting_key(keys["setting"])
        anchors = episode_anchors(list(store.episode_dir(profile.content_hash, keys["setting"]).glob("episode_*.hdf5")))
        rows = run_rollouts(ScriptedBaseline(), setting.task, setting.embodiment, keys["channel"], anchors,
                            config.episodes, max_steps=config.max_steps)
        return _rollout_result(store, rows, BASELINE, keys["setting"], keys["channel"], len(anchors),
                               rollout_provenance(profile.content_hash, config.max_steps))

    return rollouts


def build_policy_rollouts(settings: FactorySettings, policy: str):
    cfg = settings.policy_configs()[policy]
    RolloutConfig = rollout_config(settings)

    @dg.asset(name=f"{policy}_rollouts", partitions_def=setting_channel_partitions, group_name="evaluation",
              deps=[f"{policy}_checkpoint"], code_version="1",
              description=f"{policy.upper()} ({cfg.name}) in closed loop per channel: its views rendered online at "
                          "20 Hz, anchored on its training scenes.")
    def rollouts(context: dg.AssetExecutionContext, config: RolloutConfig,
                 store: EpisodeStore) -> dg.MaterializeResult:
        from policies.learned import LearnedPolicy

        keys = context.partition_key.keys_by_dimension
        setting = parse_setting_key(keys["setting"])
        learned = LearnedPolicy(store.checkpoint_dir(policy, cfg.name, keys["setting"]))
        anchors = checkpoint_anchors(learned.checkpoint.manifest)
        rows = run_rollouts(learned, setting.task, setting.embodiment, keys["channel"], anchors,
                            config.episodes, max_steps=config.max_steps)
        return _rollout_result(store, rows, learned.name, keys["setting"], keys["channel"], len(anchors),
                               rollout_provenance(sensor_profile(cfg.observation.sensor_profile).content_hash,
                                                  config.max_steps))

    return rollouts


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
