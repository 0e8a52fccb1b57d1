"""`b2d train` and `b2d eval`: train a policy on a setting's episodes, evaluate a checkpoint in closed loop."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click

from sim import registry


def _episode_files(paths: tuple[Path, ...]) -> list[Path]:
    files = []
    for p in paths:
        files.extend(sorted(p.glob("episode_*.hdf5")) if p.is_dir() else [p])
    return files


def _default_episodes(setting: str, profile) -> list[Path]:
    """The store's episodes of the setting under the policy's profile, rendered from the stored replays
    when missing (data/replays/<setting>: `b2d materialize` or the Dagster job writes them)."""
    from b2d_pipeline.resources import EpisodeStore
    from b2d_pipeline.settings import FactorySettings
    from policies.training_data import render_policy_episodes

    store = EpisodeStore(data_root=str(FactorySettings.from_env().data_root))
    out = store.episode_dir(profile.content_hash, setting)
    have = sorted(out.glob("episode_*.hdf5"))
    replays = sorted(store.replay_dir(setting).glob("*.replay.h5"))
    missing = [r for r in replays if not (out / r.name.replace(".replay.h5", ".hdf5")).exists()]
    if missing:
        with click.progressbar(length=len(missing), label=f"rendering {len(missing)} replays under "
                               f"'{profile.name}'", file=sys.stderr, show_eta=True) as bar:
            _, errors = render_policy_episodes(missing, profile, out, progress=bar.update)
        for name, msg in errors.items():
            click.echo(f"error: {name}: {msg}", err=True)
        have = sorted(out.glob("episode_*.hdf5"))
    return have


@click.command()
@click.option("--setting", required=True, help="Setting key <task>__<embodiment>.")
@click.option("--policy", "policy_name", required=True, type=click.Choice(["act", "dp"]))
@click.option("--config", "config_name", default="tiny", show_default=True,
              help="Config name (policies/configs/<policy>/) or a YAML file.")
@click.option("--out", "out_dir", required=True, type=click.Path(path_type=Path))
@click.option("--episodes", "episode_paths", multiple=True, type=click.Path(exists=True, path_type=Path),
              help="HDF5 episodes or folders of them rendered under the config's sensor profile "
                   "(default: the store's, rendered from data/replays/<setting> when missing).")
@click.option("--steps", default=None, type=click.IntRange(min=1), help="Override the config's training steps.")
def train(setting, policy_name, config_name, out_dir, episode_paths, steps) -> None:
    """Train ACT or Diffusion Policy on a setting's episodes into a checkpoint folder."""
    from policies.config import load_policy_config
    from policies.train import train_policy

    parsed = registry.parse_setting_key(setting)
    cfg = load_policy_config(policy_name, config_name)
    profile = registry.sensor_profile(cfg.observation.sensor_profile)
    files = _episode_files(episode_paths) if episode_paths else _default_episodes(setting, profile)
    if not files:
        raise click.UsageError(f"no episodes of {setting} under sensor profile '{profile.name}': pass --episodes "
                               f"or materialize the setting's replays first (b2d materialize --setting {setting})")
    total = steps or cfg.train.steps
    with click.progressbar(length=total, label=f"training {cfg.policy} {cfg.name} on {len(files)} episodes",
                           file=sys.stderr, show_eta=True) as bar:
        result = train_policy(cfg, files, out_dir, progress=bar.update, steps=steps)
    from policies.checkpoint import load_checkpoint
    ckpt = load_checkpoint(result.checkpoint)
    if (ckpt.task, ckpt.embodiment) != (parsed.task, parsed.embodiment):
        click.echo(f"warning: the episodes are of {ckpt.task} on {ckpt.embodiment}, not {setting}", err=True)
    click.echo(json.dumps({"checkpoint": str(result.checkpoint), "steps": result.steps, "episodes": result.episodes,
                           "frames": result.frames, "final_loss": result.final_loss,
                           "seconds": round(result.seconds, 2), "steps_per_second": round(result.steps_per_second, 3)},
                          indent=2))


@click.command("eval")
@click.option("--checkpoint", "checkpoint_dir", default=None, type=click.Path(path_type=Path))
@click.option("--remote", default=None, help="Evaluate a running policy server instead: tcp://HOST:PORT or ws://HOST:PORT.")
@click.option("--spec", "spec_file", default=None, type=click.Path(path_type=Path),
              help="--remote: the server's policy spec (JSON/YAML), for servers that do not send it.")
@click.option("--setting", default=None, help="--remote: <task>__<embodiment>, for servers that do not name it.")
@click.option("--layout", "layout_file", default=None, type=click.Path(path_type=Path),
              help="--remote: the fixed-width layout the server speaks (YAML from `b2d layout`).")
@click.option("--channel", "channels", multiple=True, help="Channel(s); default: all four.")
@click.option("--episodes", default=10, show_default=True, type=click.IntRange(min=1), help="Rollouts per channel.")
@click.option("--max-steps", default=None, type=click.IntRange(min=1), help="Cap on control steps per episode.")
@click.option("--out", "out_file", default=None, type=click.Path(path_type=Path),
              help="Write the per-episode records (parquet) here.")
@click.option("--json", "as_json", is_flag=True, help="Print the per-channel metrics as JSON.")
def eval_cmd(checkpoint_dir, remote, spec_file, setting, layout_file, channels, episodes, max_steps, out_file, as_json) -> None:
    """Evaluate a checkpoint (or a policy server) in closed loop under generalization channels, anchored on
    its training scenes."""
    import pandas as pd

    from evaluation.metrics import cell_metrics
    from policies.anchors import checkpoint_anchors
    from policies.learned import LearnedPolicy
    from policies.records import records_frame, write_records
    from policies.rollouts import run_rollouts

    for c in channels:
        registry.validate_name("channel", c)
    if (checkpoint_dir is None) == (remote is None):
        raise click.UsageError("pass --checkpoint DIR or --remote URL")
    if remote:
        from policies.interface import PolicyError
        from policies.remote.target import remote_target
        try:
            policy, task, embodiment, anchors = remote_target(remote, spec_file, setting, layout_file)
        except (PolicyError, ValueError) as exc:
            raise click.UsageError(str(exc)) from exc
    else:
        policy = LearnedPolicy(checkpoint_dir)
        task, embodiment, anchors = policy.checkpoint.task, policy.checkpoint.embodiment, \
            checkpoint_anchors(policy.checkpoint.manifest)
    rows = []
    chans = list(channels) or registry.channel_names()
    with click.progressbar(length=episodes * len(chans), label=f"evaluating {policy.name} on {task}",
                           file=sys.stderr, show_eta=True) as bar:
        for c in chans:
            rows += run_rollouts(policy, task, embodiment, c, anchors, episodes, max_steps=max_steps,
                                 progress=bar.update)
    # provenance columns, as the pipeline's rollout records carry them: `b2d tables` reads them into its outputs
    from result_tables.provenance import rollout_provenance
    checkpoint = getattr(policy, "checkpoint", None)          # a remote policy has none
    profile_hash = checkpoint.manifest.get("profile_hash") if checkpoint is not None else None
    frame = records_frame(rows).assign(**rollout_provenance(profile_hash, max_steps))
    if out_file:
        write_records(frame, out_file)
    cells = cell_metrics(frame, by=("task", "embodiment", "policy", "channel"))
    cells = cells.sort_values("channel", key=lambda c: c.map({n: i for i, n in enumerate(registry.channel_names())}))
    cols = [c for c in ("channel", "N", "n_success", "SR", "LSCR", "CSCR", "n_error") if c in cells.columns]
    if as_json:
        click.echo(json.dumps(json.loads(cells[cols].to_json(orient="records")), indent=2))
    else:
        click.echo(cells[cols].to_string(index=False))
    if pd.isna(cells["SR"]).all():
        sys.exit(1)
