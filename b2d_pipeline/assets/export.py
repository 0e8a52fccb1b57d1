"""Each setting's HDF5 episodes as a LeRobot dataset, rebuilt whenever the episodes change.

Its own group ("export"), selected by no job, so it never lengthens a production run: the automation
sensor materializes it after the setting's episodes update (eager condition)."""


import hashlib

import dagster as dg

from b2d_pipeline.assets.common import CPU_POOL, fail_if_errors
from b2d_pipeline.partitions import settings_partitions
from b2d_pipeline.resources import EpisodeStore
from b2d_pipeline.settings import FactorySettings
from episodes.atomic import file_sha256
from lerobot_export import export_lerobot

LEROBOT_FORMAT = "v2.1"   # what GR00T N1.5 and openpi train on; `b2d export lerobot --format v3.0` for lerobot's own


def lerobot_dir(store: EpisodeStore, profile_hash: str, setting: str):
    return store.root / "lerobot" / LEROBOT_FORMAT / profile_hash / setting


def build(settings: FactorySettings):
    profile = settings.profile

    @dg.asset(partitions_def=settings_partitions, group_name="export", pool=CPU_POOL, deps=["episodes"],
              code_version=f"1-{LEROBOT_FORMAT}-{profile.content_hash}",
              automation_condition=dg.AutomationCondition.eager(),
              description=f"The setting's episodes as a LeRobot {LEROBOT_FORMAT} dataset (parquet, one MP4 per "
                          "view, tactile images, stats) with GR00T's meta/modality.json.")
    def lerobot_dataset(context: dg.AssetExecutionContext, store: EpisodeStore) -> dg.MaterializeResult:
        key = context.partition_key
        source = store.episode_dir(profile.content_hash, key)
        out = lerobot_dir(store, profile.content_hash, key)
        # the folder is this asset's own output: replacing it is the point of a rebuild
        result = export_lerobot([source], out, LEROBOT_FORMAT, overwrite=True)
        for path, message in result.errors.items():
            context.log.error(message if path in message else f"{path}: {message}")
        files = sorted(p for p in out.rglob("*") if p.is_file())
        digest = hashlib.sha256("".join(f"{p.relative_to(out)}:{file_sha256(p)}\n" for p in files).encode())
        fail_if_errors({str(k): v for k, v in result.errors.items()}, len(result.episodes))
        return dg.MaterializeResult(
            metadata={"episodes": len(result.episodes), "frames": result.frames, "format": LEROBOT_FORMAT,
                      "directory": dg.MetadataValue.path(str(out)), "files": len(files),
                      "bytes": sum(p.stat().st_size for p in files), "seconds": round(result.seconds, 2)},
            data_version=dg.DataVersion(digest.hexdigest()[:16]))

    return lerobot_dataset
