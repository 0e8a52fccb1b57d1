"""RGB-D and tactile renders of each replay under the active sensor profile."""


import dagster as dg

from b2d_pipeline.assets.common import data_version, fail_if_errors
from b2d_pipeline.partitions import settings_partitions
from b2d_pipeline.resources import EpisodeStore
from b2d_pipeline.settings import FactorySettings
from episodes.stages import render_to_file


def build(settings: FactorySettings):
    profile = settings.profile

    # The profile hash in the code version: a changed profile marks renders (and downstream) stale.
    # 2: renders carry the tactile frames (robot/tactile) when the profile enables them.
    # 3: labels (segmentation, 2D/3D boxes, occupancy) as the profile lists them.
    @dg.asset(partitions_def=settings_partitions, group_name="renders", deps=["replays"],
              code_version=f"3-{profile.content_hash}",
              description=f"Camera and tactile renders under the '{profile.name}' sensor profile "
                          f"({profile.content_hash}).")
    def renders(context: dg.AssetExecutionContext, store: EpisodeStore) -> dg.MaterializeResult:
        key = context.partition_key
        paths, errors, frames = [], {}, 0
        for rep in sorted(store.replay_dir(key).glob("*.replay.h5")):
            out = store.render_dir(profile.content_hash, key) / rep.name.replace(".replay.h5", ".render.h5")
            try:
                info = render_to_file(rep, profile, out, workers=settings.render_workers)
                frames += info["frames"]
                paths.append(out)
            except Exception as exc:
                context.log.error(f"{rep}: {exc}")
                errors[rep.name] = str(exc)
        fail_if_errors(errors, len(paths))
        described = store.describe(paths)
        return dg.MaterializeResult(
            metadata={"profile": profile.name, "profile_hash": profile.content_hash, "frames": frames,
                      "tactile": profile.tactile_enabled,
                      "files": dg.MetadataValue.json(described)},
            data_version=data_version(described, profile.content_hash))

    return renders
