"""Policy inputs and trained checkpoints per setting: one checkpoint asset per learned policy (a factory),
since Dagster's multi-partitions have two dimensions and the policy is a third."""


import dagster as dg

from b2d_pipeline.assets.common import CPU_POOL, data_version, fail_if_errors
from b2d_pipeline.partitions import settings_partitions
from b2d_pipeline.resources import EpisodeStore
from b2d_pipeline.run_config import training_config
from b2d_pipeline.settings import FactorySettings
from episodes.atomic import file_sha256
from policies.checkpoint import LOSS_PLOT, MANIFEST, WEIGHTS
from policies.train import train_policy
from policies.training_data import render_policy_episodes
from sim.registry import sensor_profile


def input_profiles(settings: FactorySettings) -> dict:
    """The sensor profiles the configured policies observe through, by name."""
    return {cfg.observation.sensor_profile: sensor_profile(cfg.observation.sensor_profile)
            for cfg in settings.policy_configs().values()}


def build_policy_inputs(settings: FactorySettings):
    profiles = input_profiles(settings)
    version = "-".join(f"{p.name}:{p.content_hash}" for p in profiles.values())

    @dg.asset(partitions_def=settings_partitions, group_name="training", deps=["replays"], pool=CPU_POOL, code_version=f"1-{version}",
              description="Training episodes at the policies' inputs: the stored replays rendered under each policy "
                          f"sensor profile ({', '.join(profiles)}).")
    def policy_inputs(context: dg.AssetExecutionContext, store: EpisodeStore) -> dg.MaterializeResult:
        key = context.partition_key
        replays = sorted(store.replay_dir(key).glob("*.replay.h5"))
        if not replays:
            raise dg.Failure(f"no replays of {key}: materialize raw_recordings and replays first")
        paths, errors = [], {}
        for profile in profiles.values():
            written, failed = render_policy_episodes(replays, profile, store.episode_dir(profile.content_hash, key))
            paths += written
            errors.update({f"{profile.name}/{k}": v for k, v in failed.items()})
        fail_if_errors(errors, len(paths))
        described = store.describe(paths)
        return dg.MaterializeResult(
            metadata={"episodes": len(paths), "profiles": dg.MetadataValue.json({n: p.content_hash
                                                                                 for n, p in profiles.items()}),
                      "files": dg.MetadataValue.json(described)},
            data_version=data_version(described))

    return policy_inputs


def build_checkpoint(settings: FactorySettings, policy: str):
    cfg = settings.policy_configs()[policy]
    profile = sensor_profile(cfg.observation.sensor_profile)
    TrainingConfig = training_config(settings)

    # the config's content hash: a changed config marks the checkpoint (and rollouts) stale; the step
    # budget is run config, recorded in the checkpoint's manifest and so in its data version
    @dg.asset(name=f"{policy}_checkpoint", partitions_def=settings_partitions, group_name="training", pool=CPU_POOL,
              deps=["policy_inputs"], code_version=f"1-{cfg.content_hash}",
              description=f"{policy.upper()} ({cfg.name} config: {cfg.description}) trained on the setting's "
                          f"episodes under '{profile.name}'. Safetensors + JSON.")
    def checkpoint(context: dg.AssetExecutionContext, config: TrainingConfig,
                   store: EpisodeStore) -> dg.MaterializeResult:
        key = context.partition_key
        episodes = sorted(store.episode_dir(profile.content_hash, key).glob("episode_*.hdf5"))
        if not episodes:
            raise dg.Failure(f"no episodes of {key} under '{profile.name}': materialize policy_inputs first")
        out = store.checkpoint_dir(policy, cfg.name, key)
        result = train_policy(cfg, episodes, out, steps=config.steps or cfg.train.steps)
        curve = [{"step": r["step"], "loss": round(r["loss"], 5)} for r in result.train_log]
        return dg.MaterializeResult(
            metadata={"episodes": result.episodes, "frames": result.frames, "steps": result.steps,
                      "final_loss": result.final_loss, "steps_per_second": round(result.steps_per_second, 3),
                      "train_seconds": round(result.seconds, 1), "checkpoint": dg.MetadataValue.path(str(out)),
                      "loss_plot": dg.MetadataValue.path(str(out / LOSS_PLOT)),
                      "loss_curve": dg.MetadataValue.json(curve)},
            data_version=dg.DataVersion(file_sha256(out / WEIGHTS)[:16] + file_sha256(out / MANIFEST)[:8]))

    return checkpoint
