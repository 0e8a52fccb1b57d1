"""The torch models behind the learned policies, and which config class each one reads."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ModelEntry:
    config_class: type
    model_class: type


def config_class(policy: str) -> type:
    """The pydantic config of a learned policy's model, without importing torch."""
    if policy == "act":
        from policies.models.act_config import ACTConfig
        return ACTConfig
    if policy == "dp":
        from policies.models.diffusion_config import DiffusionConfig
        return DiffusionConfig
    from sim.errors import UnknownNameError
    raise UnknownNameError("policy", policy, ["act", "dp"])


def model_class(policy: str) -> ModelEntry:
    """The model of a learned policy ("act", "dp"); imported on demand (torch is heavy)."""
    if policy == "act":
        from policies.models.act import ACTConfig, ACTModel
        return ModelEntry(ACTConfig, ACTModel)
    if policy == "dp":
        from policies.models.diffusion import DiffusionConfig, DiffusionModel
        return ModelEntry(DiffusionConfig, DiffusionModel)
    from sim.errors import UnknownNameError
    raise UnknownNameError("policy", policy, ["act", "dp"])
