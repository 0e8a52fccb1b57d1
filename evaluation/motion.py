"""Robot-motion diagnostics (paper, "Tool-use and motion diagnostics"): root mean square over the
available updates and robot joints of joint velocity, acceleration, jerk and effort.

Velocity and effort come with each state (``SceneState.robot_qvel`` / ``robot_effort``); acceleration
and jerk are backward differences between consecutive updates (a_j = (v_j - v_{j-1}) / dt_j,
jerk_j = (a_j - a_{j-1}) / dt_j), so the first update has no acceleration and the first two no
jerk, and an update without robot state interrupts the differences. Per update the monitor only
keeps the two arrays (the evaluator runs every control step); the arithmetic is done once, over the
whole episode, when traces or the record are asked for. Values are comparable only under a shared
embodiment and timing configuration.
"""

from __future__ import annotations

import math

import numpy as np

from evaluation.errors import StateError

QUANTITIES = ("vel", "acc", "jerk", "effort")


class MotionMonitor:
    def __init__(self):
        self.reset()

    def reset(self) -> None:
        self.qvel: list[np.ndarray | None] = []
        self.effort: list[np.ndarray | None] = []
        self.width: int | None = None

    def update(self, qvel: np.ndarray | None, effort: np.ndarray | None) -> None:
        for value in (qvel, effort):
            if value is not None:
                n = len(value)
                if self.width is None:
                    self.width = n
                elif n != self.width:
                    raise StateError(f"robot state has {n} joints, earlier updates had {self.width}")
        self.qvel.append(qvel)
        self.effort.append(effort)

    def _stack(self, rows: list[np.ndarray | None]) -> np.ndarray:
        out = np.full((len(rows), self.width or 0), np.nan)
        for i, r in enumerate(rows):
            if r is not None:
                out[i] = r
        return out

    def series(self, dt: np.ndarray) -> dict[str, np.ndarray]:
        """[T, J] arrays per quantity (NaN where not available); ``dt``: [T] update lengths."""
        v = self._stack(self.qvel)
        inv = (1.0 / np.asarray(dt, dtype=float))[:, None]
        a = np.full_like(v, np.nan)
        a[1:] = (v[1:] - v[:-1]) * inv[1:]
        jerk = np.full_like(v, np.nan)
        jerk[1:] = (a[1:] - a[:-1]) * inv[1:]
        return {"vel": v, "acc": a, "jerk": jerk, "effort": self._stack(self.effort)}

    def summary(self, dt: np.ndarray) -> tuple[dict[str, np.ndarray], dict[str, float | None]]:
        """Per-update RMS over joints ([T], NaN where unavailable) and the episode RMS over updates and
        joints (None when nothing was observed)."""
        traces, episode = {}, {}
        for key, x in self.series(dt).items():
            sq = x * x
            seen = ~np.isnan(sq[:, 0]) if sq.shape[1] else np.zeros(len(sq), dtype=bool)
            per = np.full(len(sq), np.nan)
            episode[key] = None
            if seen.any():
                per[seen] = np.sqrt(sq[seen].mean(axis=1))
                episode[key] = math.sqrt(float(sq[seen].mean()))
            traces[key] = per
        return traces, episode
