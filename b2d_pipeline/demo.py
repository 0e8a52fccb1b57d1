"""Materialize the whole chain for settings, in dependency order: per setting the production assets and
the policies' checkpoints, then one run per (setting, channel) for every policy's rollouts, then the
result table."""

from __future__ import annotations

import dagster as dg

from b2d_pipeline.definitions import build_definitions
from b2d_pipeline.partitions import setting_channel_key
from b2d_pipeline.settings import FactorySettings
from sim.registry import channel_names

PRODUCTION = ["raw_recordings", "replays", "renders", "episodes"]
ROLLOUTS = ["scripted_operator_rollouts"]


def materialize_chain(settings: FactorySettings, setting_keys: list[str], instance: dg.DagsterInstance,
                      channels: list[str] | None = None, log=print) -> list[dg.ExecuteInJobResult]:
    defs = build_definitions(settings)
    assets = list(defs.assets)
    resources = defs.resources
    results = []

    def run(selection, partition_key=None):
        log(f"materializing {', '.join(selection)}" + (f" [{partition_key}]" if partition_key else ""))
        result = dg.materialize(assets, selection=selection, partition_key=partition_key, instance=instance,
                                resources=resources, raise_on_error=False)
        results.append(result)
        if not result.success:
            for event in result.all_events:
                if event.is_failure:
                    log(f"  failed: {event.message}")
        return result

    training = ["policy_inputs", *(f"{p}_checkpoint" for p in settings.policies)] if settings.policies else []
    for key in setting_keys:
        if not run(PRODUCTION + training, key).success:
            continue
        for channel in channels or channel_names():
            run(ROLLOUTS + [f"{p}_rollouts" for p in settings.policies], setting_channel_key(key, channel))
    run(["evaluation_table"])
    return results
