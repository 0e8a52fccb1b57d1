"""HDF5 episodes in the paper's layout, plus the directory's episode_manifest.json."""


import dagster as dg

from b2d_pipeline.assets.common import CPU_POOL, data_version, fail_if_errors, require_inputs
from b2d_pipeline.partitions import settings_partitions
from b2d_pipeline.resources import EpisodeStore
from b2d_pipeline.schedules import FOLLOW_UPSTREAM
from b2d_pipeline.settings import FactorySettings
from episodes import schema
from episodes.manifest import write_manifest
from episodes.stages import assemble_episode


def build(settings: FactorySettings):
    profile = settings.profile

    @dg.asset(partitions_def=settings_partitions, group_name="episodes", pool=CPU_POOL, deps=["replays", "renders"],
              code_version=f"3-{profile.content_hash}",   # 3: schema b2d.episode/2 (labels, joints, distractors)
              automation_condition=FOLLOW_UPSTREAM,
              description="Synchronized multimodal episodes (meta, time, action, cameras, robot incl. tactile, "
                          "objects, metrics).")
    def episodes(context: dg.AssetExecutionContext, store: EpisodeStore) -> dg.MaterializeResult:
        key = context.partition_key
        out_dir = store.episode_dir(profile.content_hash, key)
        paths, errors, successes = [], {}, 0
        render_dir = store.render_dir(profile.content_hash, key)
        for ren in require_inputs(sorted(render_dir.glob("*.render.h5")), render_dir, "*.render.h5", "renders"):
            stem = ren.name.removesuffix(".render.h5")
            rep = store.replay_dir(key) / f"{stem}.replay.h5"
            out = out_dir / schema.episode_filename(stem.removeprefix("episode_"))
            try:
                info = assemble_episode(rep, ren, profile, out)
                successes += info["success"]
                paths.append(out)
            except Exception as exc:
                context.log.error(f"{ren}: {exc}")
                errors[ren.name] = str(exc)
        if paths:
            write_manifest(out_dir)
        fail_if_errors(errors, len(paths))
        described = store.describe(paths)
        return dg.MaterializeResult(
            metadata={"episodes": len(paths), "successes": successes, "profile_hash": profile.content_hash,
                      "directory": dg.MetadataValue.path(str(out_dir)), "files": dg.MetadataValue.json(described)},
            data_version=data_version(described))

    return episodes
