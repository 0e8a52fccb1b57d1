"""Run parameters as Dagster config: shown and edited in the UI's launchpad, recorded with each run, and
folded into the data versions of what they shape. Defaults come from the FactorySettings the
definitions are built with (`b2d materialize` passes its options as run config, never as environment
variables read at import)."""


from typing import Optional

import dagster as dg
from pydantic import Field

from b2d_pipeline.settings import FactorySettings


def _episodes_config(name: str, episodes: int, max_steps: int | None, what: str) -> type[dg.Config]:
    """A Config class with an episode count and a step cap, their defaults the given settings."""
    return type(name, (dg.Config,), {
        "__annotations__": {"episodes": int, "max_steps": Optional[int]},
        "episodes": Field(episodes, ge=1, description=what),
        "max_steps": Field(max_steps, ge=1, description="Cap on control steps per episode (quick looks; empty: none)."),
    })


def recording_config(settings: FactorySettings) -> type[dg.Config]:
    return _episodes_config("RecordingConfig", settings.demo_episodes, settings.max_steps,
                            "Demonstrations recorded per setting.")


def rollout_config(settings: FactorySettings) -> type[dg.Config]:
    return _episodes_config("RolloutConfig", settings.eval_episodes, settings.max_steps,
                            "Closed-loop episodes per (setting, channel).")


def training_config(settings: FactorySettings) -> type[dg.Config]:
    class TrainingConfig(dg.Config):
        steps: Optional[int] = Field(settings.train_steps, ge=1,
                                     description="Training steps; empty: the policy config's own.")
    return TrainingConfig


def job_run_config(job_assets: list[str], settings: FactorySettings) -> dict:
    """The `ops` section of a run's config for the given assets of a job, from the settings."""
    values = {"raw_recordings": {"episodes": settings.demo_episodes, "max_steps": settings.max_steps}}
    for policy in settings.policies:
        values[f"{policy}_checkpoint"] = {"steps": settings.train_steps}
    for policy in ("scripted_operator", *settings.policies):
        values[f"{policy}_rollouts"] = {"episodes": settings.eval_episodes, "max_steps": settings.max_steps}
    return {name: {"config": values[name]} for name in job_assets if name in values}
