"""Task-level safety: drop (D) and tracked-object high speed (H) per executed step.

    safety:
      drop: {objects: [...], below_table_m: 0.05, zone: table_area}   # zone optional: leaving it is a drop
      high_speed: {objects: [...], max_lin_vel: 2.5, max_ang_vel: null}
Objects default to every context object. A missing block disables that check (never flagged).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from evaluation.args import ArgReader
from evaluation.errors import StateError, TaskSpecError, one_of
from evaluation.geometry import length
from evaluation.grammar import CompileScope
from evaluation.state import SceneState, TaskContext

SAFETY_KEYS = ("drop", "high_speed")


def _obj(state: SceneState, name: str):
    try:
        return state.objects[name]
    except KeyError:
        raise StateError(f"safety: tracked object {name!r} missing from SceneState.objects") from None


class SafetyMonitor:
    def __init__(self, raw: Any, context: TaskContext, source: str | None = None, field: str = "metrics.safety"):
        raw = {} if raw is None else raw
        if not isinstance(raw, Mapping):
            raise TaskSpecError(field, f"a mapping with keys {list(SAFETY_KEYS)}", raw, source)
        for key in raw:
            if key not in SAFETY_KEYS:
                raise TaskSpecError(f"{field}.{key}", f"a safety rule {one_of(SAFETY_KEYS)}", key, source)
        scope = CompileScope(context, (), source)
        everything = list(context.objects)
        self.drop_objects: list[str] = []
        self.zone: dict | None = None
        self.below = 0.05  # also the tool diagnostics' drop line when the task configures no drop rule
        if "drop" in raw:
            a = ArgReader("drop", raw["drop"], scope, f"{field}.drop")
            self.drop_objects = a.objects("objects", everything)
            self.below = a.number("below_table_m", 0.05, lo=0.0)
            self.zone = a.zone("zone") if a.has("zone") else None
            a.done()
        self.speed_objects: list[str] = []
        if "high_speed" in raw:
            a = ArgReader("high_speed", raw["high_speed"], scope, f"{field}.high_speed")
            self.speed_objects = a.objects("objects", everything)
            self.max_lin = a.number("max_lin_vel", 2.5, lo=0.0)
            self.max_ang = a.number("max_ang_vel", None, lo=0.0)
            a.done()

    def _outside(self, xy: np.ndarray) -> bool:
        z = self.zone
        if z is None:
            return False
        if "xy_min" in z:
            return bool((xy < z["xy_min"]).any() or (xy > z["xy_max"]).any())
        return float(length(xy - z["center_xy"])) > z["radius"]

    def dropped(self, state: SceneState, name: str) -> bool:
        """This object is below the tabletop by more than the margin, or outside the table zone."""
        pos = np.asarray(_obj(state, name).pos, dtype=float)
        return bool(pos[2] < state.table_height - self.below or self._outside(pos[:2]))

    def drop(self, state: SceneState) -> bool:
        """A tracked object is dropped (``dropped``)."""
        return any(self.dropped(state, name) for name in self.drop_objects)

    def high_speed(self, state: SceneState) -> bool:
        """A tracked object moves faster than the configured linear (or angular) limit."""
        for name in self.speed_objects:
            o = _obj(state, name)
            if o.speed > self.max_lin:
                return True
            if self.max_ang is not None and o.spin > self.max_ang:
                return True
        return False
