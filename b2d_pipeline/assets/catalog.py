"""What each setting is made of: its task, embodiment, arm and hand files, observed as a source.

Observing hashes the files' content per setting; the recordings depend on it, so an edited task file or
plan marks that setting's recordings (and everything after them) stale, and no other setting's.
"""

import warnings

import dagster as dg

from b2d_pipeline.partitions import settings_partitions
from sim.registry import parse_setting_key
from sim.setting_files import setting_content_hash

# Partitioned observation is marked beta in Dagster 1.13; it is the documented way to version sources.
warnings.filterwarnings("ignore", message=".*(observable_source_asset|DataVersionsByPartition)",
                        category=dg.BetaWarning)


@dg.observable_source_asset(partitions_def=settings_partitions, group_name="recordings",
                            description="Content hash of each setting's catalog files (task with its "
                                        "demonstration plan, embodiment, arm, hand).")
def setting_specs() -> dg.DataVersionsByPartition:
    versions = {}
    for key in settings_partitions.get_partition_keys():
        setting = parse_setting_key(key)
        versions[key] = dg.DataVersion(setting_content_hash(setting.task, setting.embodiment))
    return dg.DataVersionsByPartition(versions)
