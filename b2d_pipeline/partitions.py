"""Partitions: one key per task-embodiment setting, and setting x channel for evaluation."""

from __future__ import annotations

import dagster as dg

from sim.registry import channel_names, paper_settings
from sim.tasks import is_recordable


def setting_keys() -> list[str]:
    """Every available paper setting: the partitions cover the whole benchmark. A setting whose task has
    no demo_plan gets its demonstrations from a person (`b2d teleop`), not from `raw_recordings`."""
    return [s.key for s in paper_settings() if s.available]


def recordable_setting_keys() -> list[str]:
    """The settings the scripted operator can demonstrate (their task has a demo_plan): what
    `b2d materialize --all` runs."""
    return [s.key for s in paper_settings() if is_recordable(s)]


settings_partitions = dg.StaticPartitionsDefinition(setting_keys())
channel_partitions = dg.StaticPartitionsDefinition(channel_names())
setting_channel_partitions = dg.MultiPartitionsDefinition(
    {"setting": settings_partitions, "channel": channel_partitions})


def setting_channel_key(setting: str, channel: str) -> dg.MultiPartitionKey:
    return dg.MultiPartitionKey({"setting": setting, "channel": channel})
