"""Predicates on articulated-object joints ("object/joint", rad or m): joint_open, joint_closed,
joint_in_range and the stateful key_pressed_sequence."""

from __future__ import annotations

from evaluation.args import ArgReader
from evaluation.grammar import Condition, register
from evaluation.step import EvalStep

DIRECTIONS = {"positive": 1.0, "negative": -1.0}


def _direction(a: ArgReader) -> float:
    return DIRECTIONS[a.choice("direction", tuple(DIRECTIONS), "positive")]


@register("joint_open")
class JointOpen(Condition):
    """The joint is at or beyond ``threshold`` in the opening ``direction`` (positive: q >= threshold)."""

    def __init__(self, a: ArgReader):
        self.joint = a.joint("joint")
        self.threshold = a.number("threshold")
        self.sign = _direction(a)

    def __call__(self, s: EvalStep) -> bool:
        return self.sign * (s.joint(self.joint) - self.threshold) >= 0.0


@register("joint_closed")
class JointClosed(JointOpen):
    """The joint is at or short of ``threshold`` in the opening ``direction`` (positive: q <= threshold)."""

    def __call__(self, s: EvalStep) -> bool:
        return self.sign * (s.joint(self.joint) - self.threshold) <= 0.0


@register("joint_in_range")
class JointInRange(Condition):
    """min <= q <= max."""

    def __init__(self, a: ArgReader):
        self.joint = a.joint("joint")
        self.lo = a.number("min")
        self.hi = a.number("max")
        if self.hi < self.lo:
            raise a.error("max", f"a number >= min ({self.lo})", self.hi)

    def __call__(self, s: EvalStep) -> bool:
        return self.lo <= s.joint(self.joint) <= self.hi


@register("key_pressed_sequence")
class KeyPressedSequence(Condition):
    """The keys are pressed and released in the listed order (repeats allowed: C, C, G, ...).

    A key is down once it passes ``press_threshold`` in ``direction`` and up again once it is back
    short of ``release_threshold`` (default: half the press threshold, for keys resting at 0). Each
    listed key counts when it goes down while it is the next one expected and then comes up; the
    predicate is true from the release of the last key on. Other presses are ignored, unless
    ``strict: true``: a press of a listed key out of order restarts the sequence (that press may
    itself start it again).
    """

    stateful = True

    def __init__(self, a: ArgReader):
        self.keys = a.joints("keys")
        self.press = a.number("press_threshold")
        self.release = a.number("release_threshold", self.press / 2.0)
        self.sign = _direction(a)
        self.strict = a.flag("strict", False)
        if self.sign * (self.press - self.release) < 0:
            raise a.error("release_threshold", f"a value short of press_threshold ({self.press})", self.release)
        self.unique = list(dict.fromkeys(self.keys))
        self.reset()

    def reset(self) -> None:
        self.down = {k: False for k in self.unique}
        self.restart()

    def restart(self) -> None:
        """The sequence starts again; a key held down now counts only once it is pressed again."""
        self.index = 0  # next expected position in self.keys
        self.pending: str | None = None  # expected key that is down, waiting for its release
        self.done = False

    def __call__(self, s: EvalStep) -> bool:
        pressed = []
        for k in self.unique:
            q = self.sign * s.joint(k)
            was = self.down[k]
            if q >= self.sign * self.press:
                self.down[k] = True
            elif q < self.sign * self.release:
                self.down[k] = False
            if self.down[k] and not was:
                pressed.append(k)
        if self.done:
            return True
        if self.pending is not None and not self.down[self.pending]:
            self.pending, self.index = None, self.index + 1
            if self.index == len(self.keys):
                self.done = True
                return True
        for k in pressed:
            if self.pending is None and k == self.keys[self.index]:
                self.pending = k
            elif self.strict and k != self.pending:
                self.index, self.pending = 0, (k if k == self.keys[0] else None)
        return False
