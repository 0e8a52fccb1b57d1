"""The runtime view a condition sees at one evaluator update."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from evaluation.errors import StateError
from evaluation.geometry import length, rotation
from evaluation.state import HANDS, ObjectInfo, ObjectState, SceneState, TaskContext, contact


@dataclass(frozen=True)
class Target:
    """A compiled reference to an object centre or a named point."""

    kind: str  # "object" or "point"
    name: str


@dataclass
class EvalStep:
    """One update: the state, the episode's static facts and the stage values computed so far."""

    state: SceneState
    context: TaskContext
    initial: SceneState
    dt: float
    stage_value: Mapping[str, bool]  # current predicate value of each stage evaluated so far this step
    latched: Mapping[str, bool]  # latched flags after this step's closure (terminal only)
    memo: dict = field(default_factory=dict)  # per-update results shared by the monitors (e.g. "held")

    def obj(self, name: str) -> ObjectState:
        try:
            return self.state.objects[name]
        except KeyError:
            raise StateError(f"object {name!r} missing from SceneState.objects at t={self.state.time_s}") from None

    def initial_obj(self, name: str) -> ObjectState:
        try:
            return self.initial.objects[name]
        except KeyError:
            raise StateError(f"object {name!r} missing from the initial SceneState") from None

    def info(self, name: str) -> ObjectInfo:
        return self.context.objects[name]

    def joint(self, name: str) -> float:
        try:
            return float(self.state.joints[name])
        except KeyError:
            raise StateError(f"joint {name!r} missing from SceneState.joints at t={self.state.time_s}") from None

    def target_pos(self, target: Target, offset: np.ndarray | None = None) -> np.ndarray:
        """World position of a target; ``offset`` is in the object's frame, or world for points."""
        if target.kind == "object":
            o = self.obj(target.name)
            pos = np.asarray(o.pos, dtype=float)
            return pos if offset is None else pos + rotation(o.quat) @ offset
        pos = np.array(self.context.points[target.name], dtype=float)
        if target.name in self.context.table_relative_points:
            pos[2] += self.state.table_height
        return pos if offset is None else pos + offset

    def held_by(self, name: str, hand: str, hand_max_dist: float) -> bool:
        """Held proxy: the object touches the hand, or the palm centre is within ``hand_max_dist``."""
        pos = np.asarray(self.obj(name).pos, dtype=float)
        for h in HANDS if hand == "any" else (hand,):
            if contact(self.state, name, f"{h}_hand"):
                return True
            palm = self.state.hands.get(h)
            if palm is not None and length(np.asarray(palm, dtype=float) - pos) <= hand_max_dist:
                return True
        return False
