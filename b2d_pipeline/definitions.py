"""Assemble the factory's Dagster definitions; nothing else lives here."""

from __future__ import annotations


import dagster as dg

from b2d_pipeline import checks, jobs, schedules
from b2d_pipeline.assets import catalog, episodes, teleop, evaluation, recordings, renders, replays, training
from b2d_pipeline.assets import export as export_assets
from b2d_pipeline.json_io import JsonIOManager
from b2d_pipeline.ops.render_replays import JSON_IO
from b2d_pipeline.resources import EpisodeStore
from b2d_pipeline.scale_out.executors import executor_named
from b2d_pipeline.settings import FactorySettings, use_default_dagster_home


def build_definitions(settings: FactorySettings | None = None) -> dg.Definitions:
    settings = settings or FactorySettings.from_env()
    episodes_asset = episodes.build(settings)
    checkpoints = [training.build_checkpoint(settings, p) for p in settings.policies]
    rollouts = [evaluation.build_baseline_rollouts(settings)] + [
        evaluation.build_policy_rollouts(settings, p) for p in settings.policies]
    return dg.Definitions(
        assets=[catalog.setting_specs, recordings.build(settings), replays.build(), renders.build(settings), episodes_asset,
                training.build_policy_inputs(settings), *checkpoints, *rollouts, evaluation.build_table(rollouts),
                export_assets.build(settings), teleop.build(settings)],
        asset_checks=checks.build(settings, episodes_asset),
        jobs=jobs.ALL,
        executor=executor_named(settings.executor),
        sensors=[schedules.automation_sensor, schedules.new_teleop_recordings],
        resources={"store": EpisodeStore(data_root=str(settings.data_root)),
                   JSON_IO: JsonIOManager(base_dir=str(settings.data_root / "step_outputs"))},
    )


_settings = FactorySettings.from_env()
use_default_dagster_home(_settings.data_root)
defs = build_definitions(_settings)
