"""Diffusion Policy's network and noise-schedule sizes, apart from the model so that reading a policy
config needs no torch."""

from __future__ import annotations

from typing import Literal

import pydantic
from pydantic import ConfigDict, Field, PositiveInt, model_validator


class DiffusionConfig(pydantic.BaseModel):
    """Network and noise-schedule sizes; the defaults are the tiny CPU configuration."""

    model_config = ConfigDict(extra="forbid")

    backbone_width: PositiveInt = 16                 # ResNet-18 base width (64 is the standard one)
    down_dims: list[PositiveInt] = Field(default_factory=lambda: [32, 64, 128], min_length=1)
    diffusion_step_embed_dim: PositiveInt = 32
    kernel_size: PositiveInt = 5
    n_groups: PositiveInt = 8
    num_train_timesteps: PositiveInt = 100
    num_inference_steps: PositiveInt = 10
    beta_schedule: Literal["linear", "scaled_linear", "squaredcos_cap_v2"] = "squaredcos_cap_v2"
    prediction_type: Literal["epsilon", "sample"] = "epsilon"
    inference_scheduler: Literal["ddim", "ddpm"] = "ddim"
    clip_sample: bool = True
    image_pooling: Literal["spatial_softmax", "avg"] = "spatial_softmax"
    n_keypoints: PositiveInt = 32                    # spatial-softmax keypoints per view
    image_feature_dim: PositiveInt = 64              # per view and observation step
    tactile_feature_dim: PositiveInt = 16            # per tactile site and observation step

    @model_validator(mode="after")
    def _consistent(self):
        if self.num_inference_steps > self.num_train_timesteps:
            raise ValueError(f"num_inference_steps ({self.num_inference_steps}) exceeds num_train_timesteps "
                             f"({self.num_train_timesteps})")
        uneven = [d for d in self.down_dims if d % self.n_groups]
        if uneven:
            raise ValueError(f"down_dims {uneven} are not divisible by n_groups ({self.n_groups})")
        if self.diffusion_step_embed_dim % 2:
            raise ValueError("diffusion_step_embed_dim must be even (sine and cosine halves)")
        if self.kernel_size % 2 == 0:
            raise ValueError("kernel_size must be odd, so convolutions keep the sequence length")
        return self
