"""Predicates on one object's pose, motion and holding: upright, aligned, tilted_over, at_rest,
lifted, moved, held, held_near, in_contact."""

from __future__ import annotations

import numpy as np

from evaluation.args import ArgReader
from evaluation.geometry import (Z_UP, angle_deg, axis_extent, length, masked_distance, rotation, tilt_deg,
                                 vertical_half_extent)
from evaluation.grammar import Condition, register
from evaluation.state import HANDS, contact
from evaluation.step import EvalStep

AXES = ("xy", "xyz", "z")
HAND_CHOICES = (*HANDS, "any")


@register("upright")
class Upright(Condition):
    """The object's local up axis is within ``max_tilt_deg`` of world +z."""

    def __init__(self, a: ArgReader):
        self.object = a.object("object")
        self.max_tilt = a.number("max_tilt_deg", 30.0, lo=0.0, hi=180.0)
        self.up_axis = a.vector3("up_axis", [0.0, 0.0, 1.0], unit=True)

    def __call__(self, s: EvalStep) -> bool:
        return tilt_deg(s.obj(self.object).quat, self.up_axis) <= self.max_tilt


@register("aligned")
class Aligned(Condition):
    """A local axis of the object points along a world direction within ``max_angle_deg``."""

    def __init__(self, a: ArgReader):
        self.object = a.object("object")
        self.axis = a.vector3("axis", unit=True)
        self.direction = a.vector3("direction", unit=True)
        self.max_angle = a.number("max_angle_deg", lo=0.0, hi=180.0)

    def __call__(self, s: EvalStep) -> bool:
        return angle_deg(rotation(s.obj(self.object).quat) @ self.axis, self.direction) <= self.max_angle


def _mouth_axis(info) -> np.ndarray:
    axis = info.mouth_axis
    axis = Z_UP if axis is None else np.asarray(axis, dtype=float)
    return axis / length(axis)


@register("tilted_over")
class TiltedOver(Condition):
    """Pouring pose: the mouth axis is tilted at least ``min_tilt_deg`` from +z and the mouth point
    (bounding-box surface along the mouth axis) lies within ``radius`` of the target in xy."""

    def __init__(self, a: ArgReader):
        self.object = a.object("object")
        self.target = a.target("target")
        self.min_tilt = a.number("min_tilt_deg", 50.0, lo=0.0, hi=180.0)
        self.radius = a.number("radius", lo=0.0)
        info = a.scope.context.objects[self.object]
        self.axis = _mouth_axis(info)
        self.mouth_local = self.axis * axis_extent(self.axis, np.asarray(info.half_extents, dtype=float))

    def __call__(self, s: EvalStep) -> bool:
        o = s.obj(self.object)
        if tilt_deg(o.quat, self.axis) < self.min_tilt:
            return False
        mouth = np.asarray(o.pos, dtype=float) + rotation(o.quat) @ self.mouth_local
        return masked_distance(mouth, s.target_pos(self.target), "xy") <= self.radius


@register("at_rest")
class AtRest(Condition):
    """Every listed object moves slower than ``max_lin_vel`` (m/s) and ``max_ang_vel`` (rad/s)."""

    def __init__(self, a: ArgReader):
        self.objects = a.objects("objects")
        self.max_lin = a.number("max_lin_vel", 0.05, lo=0.0)
        self.max_ang = a.number("max_ang_vel", 0.5, lo=0.0)

    def __call__(self, s: EvalStep) -> bool:
        states = [s.obj(n) for n in self.objects]
        return all(o.speed <= self.max_lin and o.spin <= self.max_ang for o in states)


@register("lifted")
class Lifted(Condition):
    """The object centre is at least ``min_height`` above its initial height."""

    def __init__(self, a: ArgReader):
        self.object = a.object("object")
        self.min_height = a.number("min_height", 0.05, lo=0.0)

    def __call__(self, s: EvalStep) -> bool:
        return s.obj(self.object).pos[2] - s.initial_obj(self.object).pos[2] >= self.min_height


@register("moved")
class Moved(Condition):
    """The object centre is at least ``min_dist`` from its initial position (over ``axes``)."""

    def __init__(self, a: ArgReader):
        self.object = a.object("object")
        self.min_dist = a.number("min_dist", lo=0.0)
        self.axes = a.choice("axes", AXES, "xy")

    def __call__(self, s: EvalStep) -> bool:
        return masked_distance(s.obj(self.object).pos, s.initial_obj(self.object).pos, self.axes) >= self.min_dist


def clearance(s: EvalStep, name: str) -> float:
    """Gap between the object's bounding-box bottom and the tabletop."""
    o = s.obj(name)
    return float(o.pos[2] - vertical_half_extent(o.quat, s.info(name).half_extents) - s.state.table_height)


@register("held")
class Held(Condition):
    """Off the table by ``min_clearance`` and held by a hand (contact, or palm within ``hand_max_dist``)."""

    def __init__(self, a: ArgReader):
        self.object = a.object("object")
        self.hand = a.choice("hand", HAND_CHOICES, "any")
        self.min_clearance = a.number("min_clearance", 0.02, lo=0.0)
        self.hand_max_dist = a.number("hand_max_dist", 0.12, lo=0.0)

    def __call__(self, s: EvalStep) -> bool:
        return clearance(s, self.object) >= self.min_clearance and s.held_by(self.object, self.hand, self.hand_max_dist)


@register("held_near")
class HeldNear(Condition):
    """Off the table by ``min_clearance`` and within ``max_dist`` of the target; with ``hand`` also
    held by that hand (left, right or any)."""

    def __init__(self, a: ArgReader):
        self.object = a.object("object")
        self.target = a.target("target")
        self.max_dist = a.number("max_dist", lo=0.0)
        self.axes = a.choice("axes", AXES, "xyz")
        self.hand = a.choice("hand", HAND_CHOICES, None)
        self.min_clearance = a.number("min_clearance", 0.02, lo=0.0)
        self.hand_max_dist = a.number("hand_max_dist", 0.12, lo=0.0)

    def __call__(self, s: EvalStep) -> bool:
        near = masked_distance(s.obj(self.object).pos, s.target_pos(self.target), self.axes) <= self.max_dist
        lifted = clearance(s, self.object) >= self.min_clearance
        held = self.hand is None or s.held_by(self.object, self.hand, self.hand_max_dist)
        return near and lifted and held


@register("in_contact")
class InContact(Condition):
    """The object touches ``other``: an object, 'table', 'left_hand', 'right_hand' or 'any_hand'."""

    def __init__(self, a: ArgReader):
        self.object = a.object("object")
        self.other = a.contact_name("other")

    def __call__(self, s: EvalStep) -> bool:
        others = [f"{h}_hand" for h in HANDS] if self.other == "any_hand" else [self.other]
        return any(contact(s.state, self.object, o) for o in others)
