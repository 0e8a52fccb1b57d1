"""The factory's run settings, read once from the environment when the code location loads.

The active sensor profile is part of the code location (not run config) on purpose: its content
hash is the render assets' code version, so editing or switching the profile marks the renders
and everything downstream stale in the UI.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from sim.registry import SensorProfile, sensor_profile

REPO_ROOT = Path(__file__).resolve().parent.parent


@dataclass(frozen=True)
class FactorySettings:
    """What the code location is built from (read from the environment: the data root, the sensor
    profile, the policies) and the defaults of the run parameters (Dagster config, b2d_pipeline/run_config.py;
    never read from the environment: `b2d materialize` passes them as run config)."""

    data_root: Path
    profile: SensorProfile
    demo_episodes: int = 2      # run config default: raw recordings per setting
    eval_episodes: int = 1      # run config default: rollouts per (setting, channel)
    max_steps: int | None = None   # run config default: cap on control steps per episode (tests, quick looks)
    render_workers: int = 1     # processes rendering one episode's frames (same arrays for any count)
    policies: tuple[str, ...] = ("act", "dp")   # learned policies trained and evaluated per setting
    policy_config: str = "tiny"                 # their config (policies/configs/<policy>/<name>.yaml)
    train_steps: int | None = None              # run config default: override the config's training steps
    executor: str = "default"                   # where steps run: b2d_pipeline/scale_out/executors.py

    @classmethod
    def from_env(cls, **overrides) -> "FactorySettings":
        return cls.from_mapping(os.environ, **overrides)

    @classmethod
    def from_mapping(cls, env, **overrides) -> "FactorySettings":
        """Settings from an environment-like mapping (`to_env`'s keys), then the overrides."""
        values = dict(
            data_root=Path(env.get("B2D_DATA_ROOT", REPO_ROOT / "data")),
            profile=sensor_profile(env.get("B2D_PROFILE", "preview")),
            render_workers=int(env.get("B2D_RENDER_WORKERS", "1")),
            policies=tuple(p for p in env.get("B2D_POLICIES", "act,dp").split(",") if p),
            policy_config=env.get("B2D_POLICY_CONFIG", "tiny"),
            executor=env.get("B2D_EXECUTOR", "default"),
        )
        values.update(overrides)
        if isinstance(values["profile"], str):
            values["profile"] = sensor_profile(values["profile"])
        values["policies"] = tuple(values["policies"])
        return cls(**values)

    def to_env(self) -> dict[str, str]:
        """The environment that `from_env` reads the code location's settings back from: how a run's step
        processes (Dagster's multiprocess executor) rebuild the same definitions."""
        return {"B2D_DATA_ROOT": str(self.data_root), "B2D_PROFILE": self.profile.name,
                "B2D_RENDER_WORKERS": str(self.render_workers), "B2D_POLICIES": ",".join(self.policies),
                "B2D_POLICY_CONFIG": self.policy_config, "B2D_EXECUTOR": self.executor}

    def policy_configs(self) -> dict:
        """{policy: its PolicyConfig} of the learned policies in use; unknown names fail fast."""
        from policies.config import load_policy_config
        return {p: load_policy_config(p, self.policy_config) for p in self.policies}


def default_dagster_home(data_root: Path | None = None) -> Path:
    return Path(data_root or REPO_ROOT / "data") / "dagster_home"


def use_default_dagster_home(data_root: Path | None = None) -> Path:
    """DAGSTER_HOME follows B2D_DATA_ROOT unless set, so a separate data root keeps its own run
    history. Returns the folder in use (not created here: importing definitions writes nothing)."""
    return Path(os.environ.setdefault("DAGSTER_HOME", str(default_dagster_home(data_root))))
