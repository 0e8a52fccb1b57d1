"""Kinematic grasp stability index (paper, "Grasp diagnostics"): G = L * H * M * Q * A per object.

    L  1 if the object is at least lift_min above its initial height, else 0
    H  1 held, 0.35 lifted and stable, 0.15 lifted only, 0 otherwise
    M  exp(-(|v| / sigma_v + |w| / sigma_w) / 2)
    Q  0.75 + 0.25 min(1, d / hold_min_s) while held (d: current hold duration), else 1
    A  1 - min(1, s / max_slips) (s: slip events so far; a slip starts when the object moves relative
       to the nearest palm faster than slip_speed while held)
"Held" is the shared proxy: lifted and touching a hand, or the palm centre within hand_max_dist.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from evaluation.args import ArgReader
from evaluation.geometry import length
from evaluation.grammar import CompileScope
from evaluation.state import ObjectState, TaskContext
from evaluation.step import EvalStep

DEFAULTS = {"lift_min": 0.02, "hand_max_dist": 0.12, "stable_lin_vel": 0.05, "stable_ang_vel": 0.5,
            "sigma_v": 0.25, "sigma_w": 2.0, "hold_min_s": 0.5, "slip_speed": 0.1, "max_slips": 3.0}


def lifted_and_held(s: EvalStep, name: str, lift_min: float, hand_max_dist: float) -> bool:
    """The one "held" decision of the grasp and tool diagnostics: the object is at least ``lift_min``
    above its initial height and touches a hand or has a palm centre within ``hand_max_dist``.
    Computed once per update and object (``EvalStep.memo``)."""
    key = ("held", name, lift_min, hand_max_dist)
    held = s.memo.get(key)
    if held is None:
        lifted = s.obj(name).pos[2] - s.initial_obj(name).pos[2] >= lift_min
        held = s.memo[key] = bool(lifted and s.held_by(name, "any", hand_max_dist))
    return held


def steady(o: ObjectState, cfg: dict) -> bool:
    """Linear and angular speed within the grasp block's stable_lin_vel / stable_ang_vel."""
    return o.speed <= cfg["stable_lin_vel"] and o.spin <= cfg["stable_ang_vel"]


class GraspMonitor:
    def __init__(self, raw: Any, context: TaskContext, source: str | None = None, field: str = "metrics.grasp"):
        a = ArgReader("grasp", raw, CompileScope(context, (), source), field)
        self.objects = a.objects("objects")
        self.cfg = {k: a.number(k, v, lo=0.0) for k, v in DEFAULTS.items()}
        for k in ("sigma_v", "sigma_w", "hold_min_s", "max_slips"):
            if self.cfg[k] <= 0:
                raise a.error(k, "a positive number", self.cfg[k])
        a.done()
        self.reset()

    def reset(self) -> None:
        # plain Python lists: the per-object bookkeeping below runs every update, and numpy scalar
        # reads and writes cost several times more than list items (same IEEE arithmetic)
        n = len(self.objects)
        self.hold_s = [0.0] * n
        self.slips = [0] * n
        self.slipping = [False] * n
        self.prev_rel: list[np.ndarray | None] = [None] * n

    def _palm_offset(self, s: EvalStep, pos: np.ndarray) -> np.ndarray | None:
        rels = [pos - np.asarray(p, float) for p in s.state.hands.values()]
        return min(rels, key=length) if rels else None     # = np.linalg.norm for vectors, bit for bit

    def update(self, s: EvalStep) -> np.ndarray:
        c = self.cfg
        lift_min, hand_max_dist, dt = c["lift_min"], c["hand_max_dist"], s.dt
        scores = []
        for i, name in enumerate(self.objects):
            o = s.obj(name)
            pos = np.asarray(o.pos, dtype=float)
            v, w = o.speed, o.spin
            lifted = pos[2] - s.initial_obj(name).pos[2] >= lift_min
            held = lifted_and_held(s, name, lift_min, hand_max_dist)
            stable = v <= c["stable_lin_vel"] and w <= c["stable_ang_vel"]
            hold = self.hold_s[i] = self.hold_s[i] + dt if held else 0.0
            rel = self._palm_offset(s, pos) if held else None
            slipping = False
            if rel is not None and self.prev_rel[i] is not None:
                slipping = float(length(rel - self.prev_rel[i])) / dt > c["slip_speed"]
            self.slips[i] += int(slipping and not self.slipping[i])
            self.slipping[i], self.prev_rel[i] = slipping, rel
            big_l = 1.0 if lifted else 0.0
            big_h = 1.0 if held else 0.35 if lifted and stable else 0.15 if lifted else 0.0
            big_m = math.exp(-0.5 * (v / c["sigma_v"] + w / c["sigma_w"]))
            big_q = 0.75 + 0.25 * min(1.0, hold / c["hold_min_s"]) if held else 1.0
            big_a = 1.0 - min(1.0, self.slips[i] / c["max_slips"])
            scores.append(big_l * big_h * big_m * big_q * big_a)
        return np.array(scores, dtype=float)
