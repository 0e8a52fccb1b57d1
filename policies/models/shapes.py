"""Tensor shapes a policy model is built for (shared by the ACT and Diffusion Policy models)."""

from __future__ import annotations

import numbers
from dataclasses import dataclass, fields


@dataclass(frozen=True)
class ModelShapes:
    """Sizes of one training sample: ``n_views`` RGB images of ``image_height`` x ``image_width``, a
    ``state_dim`` proprioceptive vector over ``n_obs_steps`` steps, a chunk of ``horizon`` actions of
    ``action_dim``, and optionally ``n_tactile`` one-channel tactile maps of ``tactile_height`` x
    ``tactile_width``."""

    n_views: int
    image_height: int
    image_width: int
    state_dim: int
    action_dim: int
    n_obs_steps: int
    horizon: int
    n_tactile: int = 0
    tactile_height: int = 0
    tactile_width: int = 0

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not isinstance(value, numbers.Integral) or isinstance(value, bool) or value < 0:
                raise ValueError(f"ModelShapes.{f.name} must be a non-negative int, got {value!r}")
        if self.n_tactile > 0 and (self.tactile_height <= 0 or self.tactile_width <= 0):
            raise ValueError("tactile_height and tactile_width must be positive when n_tactile > 0")
