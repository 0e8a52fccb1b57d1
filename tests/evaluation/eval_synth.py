"""Exact synthetic scenes for the evaluation tests (no simulator)."""

from __future__ import annotations

import math

import numpy as np

from evaluation.predicates import compile_condition
from evaluation.state import ObjectInfo, ObjectState, SceneState, TaskContext
from evaluation.step import EvalStep

TABLE_Z = 0.75
IDENTITY = (1.0, 0.0, 0.0, 0.0)


def quat_axis(axis: str, deg: float) -> tuple[float, float, float, float]:
    """wxyz quaternion of a rotation by ``deg`` about world axis x, y or z."""
    half = math.radians(deg) / 2.0
    v = [0.0, 0.0, 0.0]
    v["xyz".index(axis)] = math.sin(half)
    return (math.cos(half), *v)


def obj(pos, quat=IDENTITY, v=(0.0, 0.0, 0.0), w=(0.0, 0.0, 0.0)) -> ObjectState:
    return ObjectState(np.array(pos, float), np.array(quat, float), np.array(v, float), np.array(w, float))


def info(name, half, interior=None, offset=None, mouth=None) -> ObjectInfo:
    arr = lambda x: None if x is None else np.array(x, float)  # noqa: E731
    return ObjectInfo(name, np.array(half, float), arr(interior), arr(offset), arr(mouth))


OBJECTS = {
    "box": info("box", [0.15, 0.10, 0.06], interior=[0.13, 0.08, 0.05], offset=[0.0, 0.0, 0.01]),
    "apple": info("apple", [0.04, 0.04, 0.04]),
    "banana": info("banana", [0.09, 0.02, 0.02]),
    "plate": info("plate", [0.11, 0.11, 0.008]),
    "bottle": info("bottle", [0.03, 0.03, 0.10]),
    "glass_1": info("glass_1", [0.04, 0.04, 0.08]),
    "glass_2": info("glass_2", [0.04, 0.04, 0.08]),
    "fridge": info("fridge", [0.30, 0.30, 0.60], interior=[0.25, 0.25, 0.50], offset=[0.0, 0.0, 0.0]),
    "hammer": info("hammer", [0.15, 0.02, 0.02]),
    "block": info("block", [0.05, 0.05, 0.05]),
    "piano": info("piano", [0.40, 0.10, 0.05]),
    "keyboard": info("keyboard", [0.22, 0.07, 0.015]),
    "mouse": info("mouse", [0.06, 0.035, 0.02]),
}
ZONES = {"center": {"xy_min": [-0.1, -0.1], "xy_max": [0.1, 0.1]},
         "serve": {"center_xy": [0.4, -0.2], "radius": 0.05},
         "table_area": {"xy_min": [-0.6, -0.4], "xy_max": [0.6, 0.4]}}
POINTS = {"seat_a": np.array([0.3, 0.2, 0.85]), "seat_b": np.array([-0.3, 0.2, 0.85]),
          "spot": np.array([0.0, 0.0, 0.10])}


def context(initial: SceneState | None = None, **kw) -> TaskContext:
    return TaskContext(objects=dict(OBJECTS), zones=dict(ZONES), points=dict(POINTS), initial=initial,
                       table_relative_points=frozenset({"spot"}), **kw)


def resting(name: str, x: float = 0.0, y: float = 0.0, quat=IDENTITY, **kw) -> ObjectState:
    """The object standing on the tabletop."""
    return obj([x, y, TABLE_Z + OBJECTS[name].half_extents[2]], quat, **kw)


def scene(objects=None, joints=None, hands=None, contacts=(), t=0.0, table=TABLE_Z) -> SceneState:
    hands = {"left": np.array([-0.5, 0.0, 1.2]), "right": np.array([0.5, 0.0, 1.2])} if hands is None else hands
    return SceneState(time_s=t, objects=dict(objects or {}), joints=dict(joints or {}),
                      hands={k: np.array(v, float) for k, v in hands.items()}, table_height=table,
                      contacts=frozenset(tuple(sorted(c)) for c in contacts))


def holds(spec: dict, state: SceneState, initial: SceneState | None = None, ctx: TaskContext | None = None) -> bool:
    """Compile ``spec`` against the synthetic context and evaluate it on one state."""
    ctx = ctx or context()
    cond = compile_condition(spec, ctx)
    return bool(cond(EvalStep(state, ctx, initial or state, 0.01, {}, {})))


def run(cond, states, ctx: TaskContext | None = None) -> list[bool]:
    """Evaluate a compiled (stateful) condition over a state sequence."""
    ctx = ctx or context()
    return [bool(cond(EvalStep(s, ctx, states[0], 0.01, {}, {}))) for s in states]
