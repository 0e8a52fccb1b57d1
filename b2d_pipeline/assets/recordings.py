"""Raw teleoperation recordings (scripted operator) per setting."""


import dagster as dg

from b2d_pipeline.assets.common import CPU_POOL, data_version, fail_if_errors
from b2d_pipeline.partitions import settings_partitions
from b2d_pipeline.resources import EpisodeStore
from b2d_pipeline.run_config import recording_config
from b2d_pipeline.settings import FactorySettings
from sim.registry import parse_setting_key
from sim.tasks import is_recordable
from teleop.demos import record_demonstrations


def build(settings: FactorySettings):
    RecordingConfig = recording_config(settings)

    @dg.asset(partitions_def=settings_partitions, group_name="recordings", pool=CPU_POOL, code_version="1", deps=["setting_specs"],
              description="Raw demonstrations: actions, post-step states and evaluator state per step.")
    def raw_recordings(context: dg.AssetExecutionContext, config: RecordingConfig,
                       store: EpisodeStore) -> dg.MaterializeResult:
        setting = parse_setting_key(context.partition_key)
        if not is_recordable(setting):
            raise dg.Failure(description=f"{setting.key}: task '{setting.task}' has no demo_plan, so the scripted "
                             f"operator cannot record it; record it by hand with `b2d teleop` (its recordings "
                             f"become `teleop_episodes` partitions) or add a demo_plan to "
                             f"sim/catalog/tasks/{setting.task}.yaml")
        out = store.raw_dir(context.partition_key)
        results = record_demonstrations(setting.task, setting.embodiment, config.episodes, out,
                                        max_steps=config.max_steps)
        paths = [r.path for r in results if r.path]
        fail_if_errors({r.episode_id: r.error for r in results if r.error}, len(paths))
        described = store.describe(paths)
        return dg.MaterializeResult(
            metadata={"episodes": len(paths), "successes": sum(r.success for r in results),
                      "steps": [r.steps for r in results], "files": dg.MetadataValue.json(described),
                      "directory": dg.MetadataValue.path(str(out))},
            data_version=data_version(described, config.model_dump_json()))

    return raw_recordings
