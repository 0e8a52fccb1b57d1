"""Live teleoperation recordings, one dynamic partition each: a `b2d teleop` session writes
`<data_root>/teleop/<task>__<embodiment>/episode_<n>.raw.h5`; the `new_teleop_recordings` sensor
(b2d_pipeline/schedules.py) adds a partition per new file and asks for its episode, replayed and rendered
under the active sensor profile like the scripted demonstrations."""


import dagster as dg

from b2d_pipeline.assets.common import CPU_POOL
from b2d_pipeline.resources import EpisodeStore
from b2d_pipeline.settings import FactorySettings
from episodes.stages import raw_to_episode
from sim.registry import parse_setting_key

teleop_partitions = dg.DynamicPartitionsDefinition(name="teleop_recordings")


def partition_key(setting: str, stem: str) -> str:
    return f"{setting}/{stem}"


def split_key(key: str) -> tuple[str, str]:
    setting, _, stem = key.partition("/")
    return setting, stem


def build(settings: FactorySettings):
    profile = settings.profile

    @dg.asset(partitions_def=teleop_partitions, group_name="teleop", pool=CPU_POOL, code_version=f"1-{profile.content_hash}",
              description=f"One live teleoperation recording as an HDF5 episode under '{profile.name}' "
                          "(replayed, rendered, assembled).")
    def teleop_episodes(context: dg.AssetExecutionContext, store: EpisodeStore) -> dg.MaterializeResult:
        setting, stem = split_key(context.partition_key)
        parse_setting_key(setting)            # a folder not named after a setting fails here, naming the valid ones
        raw = store.teleop_dir(setting) / f"{stem}.raw.h5"
        if not raw.exists():
            raise dg.Failure(f"{raw} is gone: the partition's recording was moved or deleted")
        out_dir = store.root / "teleop_episodes" / profile.content_hash / setting
        episode = raw_to_episode(raw, profile, out_dir,
                                 work_dir=store.root / "teleop_work" / profile.content_hash / setting,
                                 workers=settings.render_workers)
        described = store.describe([episode])
        return dg.MaterializeResult(
            metadata={"recording": dg.MetadataValue.path(str(raw)), "episode": dg.MetadataValue.path(str(episode)),
                      "profile_hash": profile.content_hash, "files": dg.MetadataValue.json(described)},
            data_version=dg.DataVersion(described[episode.name]["sha256"][:16]))

    return teleop_episodes
