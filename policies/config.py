"""Policy configs: one YAML file per (policy, size) under `policies/configs/<policy>/<name>.yaml`, checked
by one pydantic schema (unknown keys, wrong types and out-of-range values are refused with the file and
the field named). `tiny` runs on a CPU (tests, the main job); `paper` holds the paper's hyper-parameters
(appendix "Policy Training Configurations") for a GPU.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Literal

import pydantic
from pydantic import Field, model_validator

from sim.errors import SpecError, UnknownNameError
from sim.registry import load_yaml
from sim.schema import CatalogModel, validate
from sim.schema.base import Bool, Int, Name, Number, Str
from sim.schema.messages import schema_error

CONFIG_ROOT = Path(__file__).parent / "configs"
LEARNED_POLICIES = ("act", "dp")


class _Strict(CatalogModel):
    """The catalog files' base (sim/schema/base.py): unknown keys refused, read-only."""


class ObservationConfig(_Strict):
    """What the policy sees. Views, resolution and rate come from `sensor_profile`, the profile its
    training episodes are rendered under; the closed-loop runner renders the same views online."""

    sensor_profile: Str
    views: tuple[Name, ...] = Field(min_length=1)
    tactile: Bool = False          # TacMap sites as extra inputs (the tactile-conditioned variant)
    n_obs_steps: Int = Field(1, ge=1, le=16)


class ActionConfig(_Strict):
    """Action chunks: `horizon` rows starting at frame offset `start` from the newest observation (1: the
    next frame's action); the runner executes `execute` rows of each chunk from row `first_executed`."""

    horizon: Int = Field(ge=1, le=256)
    start: Int = Field(1, ge=-16, le=16)
    first_executed: Int = Field(0, ge=0)
    execute: Int = Field(1, ge=1)
    temporal_ensemble_coeff: Number | None = Field(None, ge=0.0)   # ACT: weights exp(-m i), oldest first

    @model_validator(mode="after")
    def _fits(self):
        if self.first_executed + self.execute > self.horizon:
            raise ValueError(f"first_executed + execute ({self.first_executed} + {self.execute}) exceeds "
                             f"horizon ({self.horizon})")
        if self.temporal_ensemble_coeff is not None and self.execute != 1:
            raise ValueError("temporal ensembling executes one action per query: set execute to 1")
        return self


class TrainConfig(_Strict):
    steps: Int = Field(ge=1)
    batch_size: Int = Field(ge=1)
    lr: Number = Field(gt=0)
    weight_decay: Number = Field(0.0, ge=0)
    lr_schedule: Literal["constant", "cosine"] = "constant"
    warmup_steps: Int = Field(0, ge=0)
    grad_clip: Number | None = Field(None, gt=0)
    ema_decay: Number | None = Field(None, gt=0, lt=1)
    seed: Int = Field(0, ge=0)
    threads: Int = Field(1, ge=1, le=256)     # torch CPU threads: part of the config, so results are reproducible
    device: Literal["cpu", "cuda", "auto"] = "cpu"
    log_every: Int = Field(10, ge=1)


class PolicyConfig(_Strict):
    policy: Literal["act", "dp"]
    name: Str
    description: Str = ""
    observation: ObservationConfig
    action: ActionConfig
    model: dict = Field(default_factory=dict)     # checked by the policy's own model config (policies/models)
    train: TrainConfig

    @property
    def content_hash(self) -> str:
        """Hash of everything that shapes a checkpoint: the Dagster code version of checkpoints."""
        blob = json.dumps(self.model_dump(mode="json"), sort_keys=True).encode()
        return hashlib.sha256(blob).hexdigest()[:12]

    def model_config_object(self):
        """The model's own pydantic config (ACTConfig / DiffusionConfig), validated."""
        from policies.models import config_class
        return config_class(self.policy)(**self.model)


def config_names(policy: str) -> list[str]:
    _check_policy(policy)
    return sorted(p.stem for p in (CONFIG_ROOT / policy).glob("*.yaml"))


def _check_policy(policy: str) -> None:
    if policy not in LEARNED_POLICIES:
        raise UnknownNameError("policy", policy, LEARNED_POLICIES)


def load_policy_config(policy: str, name_or_path: str) -> PolicyConfig:
    """A config by name (`tiny`, `paper`) or by path to a YAML file; errors name the file and field."""
    _check_policy(policy)
    path = Path(name_or_path)
    if not (path.suffix in (".yaml", ".yml") and path.is_file()):
        names = config_names(policy)
        if name_or_path not in names:
            raise UnknownNameError(f"{policy} config", name_or_path, names)
        path = CONFIG_ROOT / policy / f"{name_or_path}.yaml"
    return parse_policy_config(load_yaml(path), path, policy)


def parse_policy_config(raw: dict, path=None, policy: str | None = None) -> PolicyConfig:
    cfg = validate(PolicyConfig, raw, path)
    from policies.models import config_class
    model_config_class = config_class(cfg.policy)
    try:   # strict here: the file's "12" or `true` where a number belongs is a mistake, not a value
        model_config_class.model_validate(cfg.model, strict=True)
    except pydantic.ValidationError as exc:
        raise schema_error(exc, path, model_config_class, prefix="model") from exc
    if policy and cfg.policy != policy:
        raise SpecError(path, "policy", f"'{policy}' (the folder it was asked from)", cfg.policy)
    return cfg
