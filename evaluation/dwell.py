"""Reach-and-stop dwell: h_j = C_j (h_{j-1} + dt_j); stable success at the first j with h_j >= dwell.

Floating-point sums of the physics step drift below round values (30 x 1/60 s sums to
0.49999999999999994), so the comparison allows DWELL_TOL; with that the paper's formula holds as
written for any dwell > 0. Stable success also requires C_j, which only matters for dwell 0.
"""

from __future__ import annotations

import logging

log = logging.getLogger(__name__)

DWELL_TOL = 1e-9  # seconds


class Dwell:
    """Accumulated dwell time of the terminal predicate and the first stable-success update."""

    def __init__(self, dwell_s: float = 0.5):
        if not dwell_s >= 0.0:
            raise ValueError(f"dwell_s must be >= 0, got {dwell_s}")
        self.dwell_s = float(dwell_s)
        self.reset()

    def reset(self) -> None:
        self.h = 0.0  # h_j
        self.elapsed = 0.0  # sum of dt over updates so far
        self.steps = 0  # j
        self.stable_step: int | None = None  # j_stable
        self.t_stable: float | None = None  # sum of dt up to j_stable
        self.ever = False  # I_e: C held at some update
        self.last = False  # F_e: C at the latest update

    @property
    def stable(self) -> bool:
        return self.stable_step is not None

    def update(self, c: bool, dt: float) -> float:
        self.steps += 1
        self.elapsed += dt
        self.h = self.h + dt if c else 0.0
        self.ever |= c
        self.last = c
        if self.stable_step is None and c and self.h >= self.dwell_s - DWELL_TOL:
            self.stable_step, self.t_stable = self.steps, self.elapsed
            log.info("stable success at update %d (t=%.4f s)", self.steps, self.elapsed)
        return self.h
