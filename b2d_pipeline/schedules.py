"""When things run without a person: declarative automation, evaluated by one sensor.

- Renders re-run when their code version changes, which carries the active sensor profile's content
  hash: switching or editing the profile re-renders every stored replay (no re-simulation), and nothing
  is re-rendered while the profile stands still (the nightly re-render this replaces ran regardless).
- Episodes follow their renders; the result table follows new rollouts; the LeRobot export follows
  its episodes.
"""

from __future__ import annotations

import dagster as dg

_AC = dg.AutomationCondition

RERENDER_ON_PROFILE_CHANGE = (
    _AC.code_version_changed().since_last_handled() & ~_AC.any_deps_missing() & ~_AC.in_progress()
).with_label("re-render when the sensor profile changes")

FOLLOW_UPSTREAM = _AC.eager().with_label("follow upstream updates")

automation_sensor = dg.AutomationConditionSensorDefinition(
    "factory_automation", target=dg.AssetSelection.all(), default_status=dg.DefaultSensorStatus.RUNNING)
