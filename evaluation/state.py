"""Plain state snapshots the evaluator works on (filled from MuJoCo by the simulator each step).

Nothing here imports the simulator: tests build these by hand with exact numbers.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evaluation.geometry import length

HANDS = ("left", "right")
TABLE = "table"  # reserved surface / contact name


@dataclass(frozen=True)
class ObjectInfo:
    """Static object facts from the task file."""

    name: str
    half_extents: np.ndarray  # (3,) local bounding-box half sizes, metres
    interior_half_extents: np.ndarray | None = None  # containers: cavity half sizes
    interior_offset: np.ndarray | None = None  # cavity centre in the object frame
    mouth_axis: np.ndarray | None = None  # bottles/pourers: local axis the mouth points along (default +z)


class _once:
    """A property computed on first access and then kept in the instance ``__dict__`` (like
    functools.cached_property without its per-access lock, which costs more than the value)."""

    def __init__(self, fget):
        self.fget, self.name = fget, fget.__name__
        self.__doc__ = fget.__doc__

    def __get__(self, obj, owner=None):
        if obj is None:
            return self
        value = obj.__dict__[self.name] = self.fget(obj)
        return value


@dataclass(frozen=True)
class ObjectState:
    pos: np.ndarray  # (3,) world
    quat: np.ndarray  # (4,) wxyz world
    lin_vel: np.ndarray  # (3,) world
    ang_vel: np.ndarray  # (3,) world

    # Speeds, computed once per state: the grasp, safety and at_rest checks each ask for them.
    @_once
    def speed(self) -> float:
        """|lin_vel|, m/s."""
        return length(self.lin_vel)

    @_once
    def spin(self) -> float:
        """|ang_vel|, rad/s."""
        return length(self.ang_vel)


@dataclass(frozen=True)
class SceneState:
    time_s: float
    objects: dict[str, ObjectState]
    joints: dict[str, float]  # articulated-object joints, key "object/joint" (rad or m)
    hands: dict[str, np.ndarray]  # "left"/"right" -> palm-centre xyz world
    table_height: float  # tabletop z, metres
    # sorted name pairs in contact this step; names are object ids, "left_hand", "right_hand", "table"
    contacts: frozenset[tuple[str, str]] = frozenset()
    # robot joints (arms and hands, a fixed order per scene) for the motion diagnostics; None: not observed
    robot_qvel: np.ndarray | None = None  # rad/s or m/s
    robot_effort: np.ndarray | None = None  # actuator force in joint space (N m or N)


@dataclass(frozen=True)
class TaskContext:
    """Static per-episode facts the predicates are compiled against."""

    objects: dict[str, ObjectInfo]
    # named regions in world x, y: {"xy_min": [x, y], "xy_max": [x, y]} or {"center_xy": [x, y], "radius": r}
    zones: dict[str, dict]
    points: dict[str, np.ndarray]  # named target points, world xyz (see table_relative_points)
    initial: SceneState | None = None  # state at episode start; the evaluator uses its first update if None
    # names of points whose z is relative to the tabletop; the evaluator adds SceneState.table_height
    table_relative_points: frozenset[str] = field(default_factory=frozenset)
    # known articulated joints "object/joint"; when None a joint's object part must name a context object
    joints: frozenset[str] | None = None


def contact(state: SceneState, a: str, b: str) -> bool:
    """Whether names ``a`` and ``b`` touch in this step (pairs are stored sorted)."""
    return (a, b) in state.contacts or (b, a) in state.contacts
