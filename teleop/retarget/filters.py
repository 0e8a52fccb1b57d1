"""The low-pass filter DexPilot puts on the hand keypoints and on the joint targets."""

from __future__ import annotations

import numpy as np


class LowPassFilter:
    """First-order low-pass ``y += alpha (x - y)``; the first sample after ``reset`` passes through
    unchanged, so a session starts without a ramp from zero. ``alpha = 1`` switches it off."""

    def __init__(self, alpha: float):
        if not 0.0 < alpha <= 1.0:
            raise ValueError(f"low-pass alpha: expected a number in (0, 1], got {alpha}")
        self.alpha = float(alpha)
        self.value: np.ndarray | None = None

    def reset(self) -> None:
        self.value = None

    def __call__(self, x) -> np.ndarray:
        x = np.asarray(x, float)
        if self.value is None:
            self.value = x.copy()
        else:
            self.value = self.value + self.alpha * (x - self.value)
        return self.value.copy()
