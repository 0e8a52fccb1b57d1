"""Run parameters as Dagster config: shown and edited in the UI's launchpad, recorded with each run, and
folded into the data versions of what they shape. Defaults come from the FactorySettings the
definitions are built with (`b2d materialize` passes its options as run config, never as environment
variables read at import)."""


from typing import Optional

import dagster as dg
from pydantic import Field

from b2d_pipeline.settings import FactorySettings


def _episodes_config(name: str, episodes: int, max_steps: int | None, what: str, **extra) -> type[dg.Config]:
    """A Config class with an episode count and a step cap, their defaults the given settings; `extra`:
    more fields as name=(type, pydantic Field)."""
    fields = {"episodes": (int, Field(episodes, ge=1, description=what)),
              "max_steps": (Optional[int], Field(max_steps, ge=1, description="Cap on control steps per episode "
                                                                              "(quick looks; empty: none).")),
              **extra}
    return type(name, (dg.Config,), {"__annotations__": {k: t for k, (t, _) in fields.items()},
                                     **{k: f for k, (_, f) in fields.items()}})


def recording_config(settings: FactorySettings) -> type[dg.Config]:
    return _episodes_config("RecordingConfig", settings.demo_episodes, settings.max_steps,
                            "Demonstrations recorded per setting.")


EPISODES_PER_STEP = 10      # a step start costs seconds; a learned policy's episode ~20 s on a core


def rollout_config(settings: FactorySettings) -> type[dg.Config]:
    per_step = Field(EPISODES_PER_STEP, ge=1, description="Episodes per step: the unit an executor spreads "
                                                          "over processes or workers.")
    return _episodes_config("RolloutConfig", settings.eval_episodes, settings.max_steps,
                            "Closed-loop episodes per (setting, channel).", episodes_per_step=(int, per_step))


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
    config = {name: {"config": value} for name, value in values.items()}
    for policy in ("scripted_operator", *settings.policies):     # graph assets: the config is their first op's
        name = f"{policy}_rollouts"
        config[name] = {"ops": {f"plan_{name}": {"config": {"episodes": settings.eval_episodes,
                                                           "max_steps": settings.max_steps}}}}
    return {name: config[name] for name in job_assets if name in config}
