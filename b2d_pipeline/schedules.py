"""When things run without a person: declarative automation, evaluated by one sensor.

- Renders re-run when their code version changes, which carries the active sensor profile's content
  hash: switching or editing the profile re-renders every stored replay (no re-simulation), and nothing
  is re-rendered while the profile stands still (the nightly re-render this replaces ran regardless).
- Episodes follow their renders; the result table follows new rollouts; the LeRobot export follows
  its episodes.
- A new live recording in `<data_root>/teleop/<setting>/` becomes a dynamic partition of
  `teleop_episodes` and a run of `ingest_teleop` (the `new_teleop_recordings` sensor).
"""

from __future__ import annotations

import dagster as dg

from b2d_pipeline.assets.teleop import partition_key, teleop_partitions
from b2d_pipeline.jobs import teleop_job
from b2d_pipeline.resources import EpisodeStore
from episodes.raw import RAW_NAME

_AC = dg.AutomationCondition

RERENDER_ON_PROFILE_CHANGE = (
    _AC.code_version_changed().since_last_handled() & ~_AC.any_deps_missing() & ~_AC.in_progress()
).with_label("re-render when the sensor profile changes")

FOLLOW_UPSTREAM = _AC.eager().with_label("follow upstream updates")

automation_sensor = dg.AutomationConditionSensorDefinition(
    "factory_automation", target=dg.AssetSelection.all(), default_status=dg.DefaultSensorStatus.RUNNING)


@dg.sensor(job=teleop_job, minimum_interval_seconds=30, default_status=dg.DefaultSensorStatus.RUNNING)
def new_teleop_recordings(context: dg.SensorEvaluationContext, store: EpisodeStore) -> dg.SensorResult:
    """Each `episode_<n>.raw.h5` under teleop/<setting>/ not yet a partition: add it and request its run.
    Recorders write to a temporary name and rename, so a file seen here is complete. A recording replaced
    under the same name (new size or time) is requested again."""
    known = set(context.instance.get_dynamic_partitions(teleop_partitions.name))
    new_keys, requests = [], []
    for raw in sorted(store.root.glob("teleop/*/episode_*.raw.h5")):
        if not RAW_NAME.fullmatch(raw.name):
            continue
        key = partition_key(raw.parent.name, raw.name.removesuffix(".raw.h5"))
        if key not in known:
            new_keys.append(key)
        stat = raw.stat()
        requests.append(dg.RunRequest(partition_key=key, run_key=f"{key}@{stat.st_mtime_ns}:{stat.st_size}"))
    return dg.SensorResult(run_requests=requests,
                           dynamic_partitions_requests=[teleop_partitions.build_add_request(new_keys)] if new_keys else [])
