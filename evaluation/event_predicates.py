"""Stateful event predicates: struck_once (a tool hits a target exactly once) and sequence
(conditions reached in order, a number of times)."""

from __future__ import annotations

import numpy as np

from evaluation.args import ArgReader
from evaluation.geometry import box_distance, length, rotation
from evaluation.grammar import Condition, register
from evaluation.state import contact
from evaluation.step import EvalStep


@register("struck_once")
class StruckOnce(Condition):
    """The tool strikes the target exactly once.

    A visit starts when the tool head (tool centre + ``head_offset`` in the tool frame) comes within
    ``radius`` of the target's bounding box and ends when it is farther than ``exit_radius`` (default
    radius + 0.02 m). A visit is a strike when the head speed reached ``min_speed`` (at the step before
    entry or during the visit) and the target responded: tool-target contact, or target speed of at
    least ``response_speed`` (with ``require_response: false`` a fast visit suffices). True while
    exactly one strike has happened: from the first strike until a second one.
    """

    stateful = True

    def __init__(self, a: ArgReader):
        self.tool = a.object("tool")
        self.target = a.object("target")
        self.min_speed = a.number("min_speed", lo=0.0)
        self.radius = a.number("radius", lo=0.0)
        self.exit_radius = a.number("exit_radius", self.radius + 0.02, lo=self.radius)
        self.head = a.vector3("head_offset", [0.0, 0.0, 0.0])
        self.response_speed = a.number("response_speed", 0.05, lo=0.0)
        self.require_response = a.flag("require_response", True)
        self.target_half = np.asarray(a.scope.context.objects[self.target].half_extents, dtype=float)
        self.reset()

    def reset(self) -> None:
        self.strikes = 0
        self.visiting = False
        self.fast = self.responded = self.counted = False
        self.prev_speed = 0.0

    def restart(self) -> None:
        """No strikes yet; a visit under way now is not one (only visits that begin later count)."""
        self.strikes = 0
        self.counted = self.counted or self.visiting

    def __call__(self, s: EvalStep) -> bool:
        tool, target = s.obj(self.tool), s.obj(self.target)
        arm = rotation(tool.quat) @ self.head
        head = np.asarray(tool.pos, float) + arm
        speed = float(length(np.asarray(tool.lin_vel, float) + np.cross(tool.ang_vel, arm)))
        dist = box_distance(head, target.pos, target.quat, self.target_half)
        if not self.visiting and dist <= self.radius:
            self.visiting, self.counted = True, False
            self.fast, self.responded = self.prev_speed >= self.min_speed, False
        if self.visiting:
            self.fast |= speed >= self.min_speed
            self.responded |= (contact(s.state, self.tool, self.target)
                               or float(length(target.lin_vel)) >= self.response_speed)
            if self.fast and (self.responded or not self.require_response) and not self.counted:
                self.strikes, self.counted = self.strikes + 1, True
            if dist > self.exit_radius:
                self.visiting = False
        self.prev_speed = speed
        return self.strikes == 1


@register("sequence")
class Sequence(Condition):
    """The ``steps`` conditions are reached in order, ``times`` full rounds; true from then on.

    With ``edge: true`` (default) a step counts only when its condition becomes true after it was
    seen false while that step was expected (from the update it became expected on): entering, not
    staying, so a ladle resting in the pot at the start is not a dip. ``edge: false`` counts a step
    as soon as its condition holds. All steps are evaluated at every update.
    """

    stateful = True

    def __init__(self, a: ArgReader):
        self.steps = a.conditions("steps")
        self.times = a.integer("times", 1)
        self.edge = a.flag("edge", True)
        self.reset()

    def children(self):
        return self.steps

    def reset(self) -> None:
        super().reset()
        self._start_over()

    def restart(self) -> None:
        super().restart()
        self._start_over()

    def _start_over(self) -> None:
        self.index, self.rounds, self.done = 0, 0, False
        self.armed = not self.edge

    def __call__(self, s: EvalStep) -> bool:
        values = [c(s) for c in self.steps]
        if self.done:
            return True
        if not values[self.index]:
            self.armed = True
        elif self.armed:
            self.index += 1
            if self.index == len(self.steps):
                self.index, self.rounds = 0, self.rounds + 1
                self.done = self.rounds == self.times
            self.armed = not self.edge or not values[self.index]
        return self.done
