"""`b2d`: everything a person does by hand with the data factory."""

from __future__ import annotations

import json
import logging
import os
import sys
from contextlib import closing
from pathlib import Path

import click

from b2d_cli import errors as cli_errors
from b2d_cli.media_cmd import export, show
from b2d_cli.lerobot_cmd import lerobot as lerobot_export_cmd
from b2d_cli.policy_cmd import eval_cmd, train
from b2d_cli.retarget_cmd import retarget
from b2d_cli.tables_cmd import tables
from b2d_cli.serve_cmd import layout, serve
from b2d_cli.tactile_cmd import tactile
from b2d_cli.tasks_cmd import tasks
from b2d_cli.teleop_cmd import teleop
from sim import registry
from sim.errors import UnknownNameError


class _Group(click.Group):
    """Turn any error into one clear message: exit code 2 for bad input, 1 for other faults (b2d_cli/errors.py)."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except (click.exceptions.ClickException, click.exceptions.Exit, click.exceptions.Abort):
            raise
        except Exception as exc:
            if cli_errors.show_traceback():
                raise
            click.echo(f"error: {cli_errors.message(exc)}", err=True)
            cli_errors.leave(cli_errors.exit_code(exc), [exc])


@click.group(cls=_Group)
@click.option("-v", "--verbose", is_flag=True, help="Log progress details.")
def cli(verbose: bool) -> None:
    """Bench2Dex data factory: record, replay, render, validate and benchmark."""
    logging.basicConfig(level=logging.INFO if verbose else logging.WARNING, format="%(levelname)s %(name)s: %(message)s")


# ---------------------------------------------------------------- list


def _rows(kind: str) -> list[dict]:
    if kind == "embodiments":
        from sim.embodiment import load_embodiment
        rows = []
        for name in registry.names("embodiments"):
            e = load_embodiment(name)
            rows.append({"name": name, "display_name": e.display_name, "arm": e.arm.name, "hand": e.hand.name})
        return rows
    if kind == "tasks":
        from sim.tasks import load_task
        rows = []
        for name in registry.names("tasks"):
            t = load_task(name)
            rows.append({"name": name, "display_name": t.display_name, "paper_embodiment": t.paper_embodiment,
                         "stages": [s["id"] for s in t.metrics.get("stages", [])]})
        return rows
    if kind == "settings":
        from sim.tasks import is_recordable, load_task
        return [{"key": s.key, "task": s.task, "embodiment": s.embodiment, "available": s.available,
                 "recordable": is_recordable(s), "draft_plan": load_task(s.task).demo_plan_draft}
                for s in registry.paper_settings()]
    if kind == "profiles":
        rows = []
        for name in registry.names("sensor_profiles"):
            p = registry.sensor_profile(name)
            rows.append({"name": name, "description": p.description, "rate_hz": p.rate_hz,
                         "cameras": list(p.camera_ids), "resolution": [p.width, p.height],
                         "tactile": list(p.tactile_shape) if p.tactile_enabled else None, "hash": p.content_hash})
        return rows
    if kind == "channels":
        return [vars(registry.channel(c)) for c in registry.channel_names()]
    if kind == "policies":
        from policies.config import LEARNED_POLICIES, config_names, load_policy_config
        rows = [{"name": "scripted_operator", "description": "privileged baseline: the scripted person, reads the "
                 "simulator, no images", "sensor_profile": None, "hash": None}]
        for policy in LEARNED_POLICIES:
            for name in config_names(policy):
                cfg = load_policy_config(policy, name)
                rows.append({"name": f"{policy}_{name}", "description": cfg.description,
                             "sensor_profile": cfg.observation.sensor_profile, "hash": cfg.content_hash})
        return rows
    raise AssertionError(kind)


@cli.command("list")
@click.argument("kind", type=click.Choice(["embodiments", "tasks", "settings", "profiles", "channels", "policies"]))
@click.option("--json", "as_json", is_flag=True, help="Print a JSON list.")
def list_cmd(kind: str, as_json: bool) -> None:
    """List embodiments, tasks, settings, sensor profiles, channels or policies (and their configs)."""
    rows = _rows(kind)
    if as_json:
        click.echo(json.dumps(rows, indent=2))
        return
    click.echo(_aligned([list(rows[0])] + [[_cell(v) for v in row.values()] for row in rows]))


def _cell(value) -> str:
    if isinstance(value, bool):
        return "yes" if value else "no"
    return ", ".join(map(str, value)) if isinstance(value, (list, tuple)) else str(value)


def _aligned(lines: list[list[str]]) -> str:
    """A header line and rows, each column as wide as its widest cell (the last one left ragged)."""
    widths = [max(len(line[i]) for line in lines) for i in range(len(lines[0]) - 1)]
    return "\n".join("  ".join([c.ljust(w) for c, w in zip(line, widths)] + [line[-1]]).rstrip() for line in lines)


# ---------------------------------------------------------------- record / replay / validate


@cli.command()
@click.option("--task", required=True)
@click.option("--embodiment", required=True)
@click.option("--episodes", default=1, show_default=True, type=click.IntRange(min=1))
@click.option("--out", "out_dir", required=True, type=click.Path(path_type=Path))
@click.option("--first-index", default=0, show_default=True, help="Index of the first episode (sets its seed).")
@click.option("--max-steps", default=None, type=click.IntRange(min=1), help="Cap each episode's control steps.")
@click.option("--operator", type=click.Choice(["stream", "scripted"]), default="stream", show_default=True,
              help="stream: the script plays the person through the teleop stream (keypoints + wrist poses -> "
                   "DexPilot + arm IK); scripted: the same plan commands the joints directly (baseline).")
def record(task, embodiment, episodes, out_dir, first_index, max_steps, operator) -> None:
    """Record raw demonstrations with the scripted operator."""
    from teleop.demos import record_demonstrations

    from episodes.atomic import clean_stale_temporaries

    registry.validate_name("task", task)
    registry.validate_name("embodiment", embodiment)
    clean_stale_temporaries(out_dir)
    with click.progressbar(length=episodes, label=f"recording {task} on {embodiment}", file=sys.stderr) as bar:
        results = record_demonstrations(task, embodiment, episodes, out_dir, max_steps=max_steps,
                                        first_index=first_index, progress=bar.update, operator=operator)
    for r in results:
        status = "error: " + r.error if r.error else ("success" if r.success else "no success")
        click.echo(f"{r.episode_id}  steps={r.steps:<5} {status}  {r.path or ''}")
    failed = [r for r in results if r.error]
    if failed:
        click.echo(f"{len(failed)} of {len(results)} episodes failed: {', '.join(r.episode_id for r in failed)}",
                   err=True)
        sys.exit(1)


@cli.command()
@click.argument("raw", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--profile", default="preview", show_default=True)
@click.option("--out", "out_dir", required=True, type=click.Path(path_type=Path))
@click.option("--max-frames", default=None, type=click.IntRange(min=1), help="Render at most this many frames per episode.")
@click.option("--workers", default=1, show_default=True, type=click.IntRange(min=1),
              help="Processes: several recordings run whole in that many at once, and one with none left "
                   "helps render the others' last ones; one recording shares its render between them (same "
                   "arrays for any count).")
@click.option("--drift-bound-m", default=0.005, show_default=True, type=click.FloatRange(min=0.0),
              help="Flag frames whose replayed object positions drift further than this from the recording.")
def replay(raw, profile, out_dir, max_frames, workers, drift_bound_m) -> None:
    """Replay raw recordings into HDF5 episodes under a sensor profile."""
    from episodes.manifest import write_manifest
    from episodes.replay_batch import replay_recordings

    prof = registry.sensor_profile(profile)
    failed, written = [], []
    done = replay_recordings(list(raw), prof, out_dir, workers=workers, max_frames=max_frames,
                             drift_bound_m=drift_bound_m)
    # closed however this ends (an error raised with its traceback too): its worker processes stop then
    with closing(done), click.progressbar(done, length=len(raw), label=f"replaying under '{profile}'",
                                          file=sys.stderr) as results:
        for path, outcome in results:
            if isinstance(outcome, Exception):    # one bad input never stops the others
                if cli_errors.show_traceback():
                    click.echo(getattr(outcome, "worker_traceback", ""), err=True)
                    raise outcome
                failed.append((path, outcome))
                click.echo(f"\nerror: {cli_errors.one_line(outcome, path)}", err=True)
            else:
                written.append(outcome)
                click.echo(f"\n{path} -> {outcome}", err=True)
    if written:
        write_manifest(out_dir, updated=written)
    cli_errors.report_batch("recordings", len(raw), failed)


@cli.command()
@click.argument("episode", nargs=-1, required=True, type=click.Path(path_type=Path))
def validate(episode) -> None:
    """Check HDF5 episodes: the schema, every dataset decoded, and the sha256 and dataset digests the
    episode_manifest.json beside each file recorded; exit 1 when any fails."""
    from episodes.validate import validate_episode

    bad = []
    for path in episode:
        try:
            problems = validate_episode(path)
        except Exception as exc:      # a check that fails is a finding about this file, not the end of the batch
            problems = [f"<file>: {cli_errors.one_line(exc)}"]
        if problems:
            bad.append(path)
            click.echo(f"{path}: INVALID ({len(problems)} problems)")
            for p in problems:
                click.echo(f"  - {path}: {p}")
        else:
            click.echo(f"{path}: ok")
    if bad:
        click.echo(f"{len(bad)} of {len(episode)} episodes invalid: {', '.join(map(str, bad))}", err=True)
    sys.exit(1 if bad else 0)


# ---------------------------------------------------------------- bench


@cli.command()
@click.argument("part", type=click.Choice(["recorder", "replay", "tactile", "tactile-replay", "labels", "media",
                                          "embodiments", "demos", "retarget", "teleop", "policy", "chain"]))
@click.option("--profile", default="preview", show_default=True, help="Sensor profile (replay, tactile-replay).")
@click.option("--steps", default=120, show_default=True,
              help="Control steps to record (recorder, replay, teleop; replay: 0 = a whole demonstration); "
                   "frames to retarget (retarget).")
@click.option("--workers", default=1, show_default=True, type=click.IntRange(min=1),
              help="replay: also render with this many processes and report the speed-up; demos: record "
                   "the seeds (with --embodiment: the cells) in this many processes.")
@click.option("--episodes", default=4, show_default=True, type=click.IntRange(min=1),
              help="demos: demonstrations per setting.")
@click.option("--setting", multiple=True, help="demos: only these setting keys (default: all 26); replay: the "
                                                "setting whose demonstration is replayed (default: the foundation).")
@click.option("--operator", type=click.Choice(["stream", "scripted"]), default="stream", show_default=True,
              help="demos: the scripted operator through the teleop stream, or its direct joint path.")
@click.option("--embodiment", "embodiment", default=None,
              help="demos: run each --setting's task (a key or a task name; default: every task with a plan) "
                   "on these embodiments ('all' or NAME[,NAME]) for --episodes seeds: a task x embodiment table.")
@click.option("--max-steps", "demo_max_steps", default=None, type=click.IntRange(min=1),
              help="demos with --embodiment: cap on control steps per episode.")
@click.option("--all-seeds", is_flag=True,
              help="demos with --embodiment: run every seed of a cell, not only until its majority is decided.")
@click.option("--policy", "policy_name", type=click.Choice(["act", "dp"]), default="act", show_default=True,
              help="policy: which learned policy.")
@click.option("--config", "config_name", default="tiny", show_default=True, help="policy: its config.")
@click.option("--train-steps", default=50, show_default=True, type=click.IntRange(min=1), help="policy: training steps.")
@click.option("--eval-episodes", default=2, show_default=True, type=click.IntRange(min=1),
              help="policy: closed-loop episodes timed (each policy and the baseline).")
def bench(part, profile, steps, workers, episodes, setting, operator, embodiment, demo_max_steps, all_seeds,
          policy_name, config_name, train_steps, eval_episodes) -> None:
    """Print benchmark figures as JSON on stdout."""
    # Per-core figures: Mesa's software GL (llvmpipe) rasterizes on one thread per core by default, so a
    # "one core" render also used the other cores (b2d bench replay --profile paper: 5.6 fps "per core"
    # that way, 4.9 on one). 0 = on the calling thread. Read when the first GL context is made, which is
    # after this; a GPU driver ignores it; an LP_NUM_THREADS already set is kept.
    os.environ.setdefault("LP_NUM_THREADS", "0")
    if part == "chain":
        from b2d_pipeline.bench import run_chain_bench
        key = setting[0] if setting else DEFAULT_SETTING
        figures = run_chain_bench(key)       # the main job as `b2d materialize` runs it, on 1 then 2 processes
    elif part == "policy":
        from policies.bench import run_policy_bench
        figures = run_policy_bench(policy_name, config_name, train_steps=train_steps, eval_episodes=eval_episodes)
    elif part == "demos" and embodiment is not None:
        from teleop.demo_bench import run_cross_embodiment_demo_bench
        figures = run_cross_embodiment_demo_bench(embodiment, list(setting), episodes, demo_max_steps, operator,
                                                  stop_when_decided=not all_seeds, processes=workers)
    elif part == "demos":
        from teleop.demo_bench import run_demo_bench
        figures = run_demo_bench(episodes=episodes, only=list(setting) or None, operator=operator, processes=workers)
    elif part == "media":
        from episode_media.bench import run_media_bench
        figures = run_media_bench(profile=profile, steps=steps)
    elif part == "teleop":
        from teleop.session_bench import run_session_bench
        figures = run_session_bench(steps=steps)
    elif part == "retarget":
        from teleop.retarget.bench import run_bench
        figures = run_bench(frames=steps, echo=False)
    elif part == "tactile":
        from tactile.bench import run_tactile_bench
        figures = run_tactile_bench()
    elif part == "embodiments":
        from sim.embodiment.bench import run_embodiment_bench
        figures = run_embodiment_bench()
    else:
        from b2d_cli import benchmarks
        figures = benchmarks.run(part, profile=profile, steps=steps, workers=workers,
                                 setting=setting[0] if setting else None)
    click.echo(json.dumps(figures, indent=2))


# ---------------------------------------------------------------- pipeline


DEFAULT_SETTING = "citrus_plate_loading__ur5_rh5dg2"     # the foundation setting: a small first run


@cli.command()
@click.option("--setting", "settings_", multiple=True, help=f"Setting key(s); default: {DEFAULT_SETTING}.")
@click.option("--all", "all_settings", is_flag=True, help="Every setting the scripted operator can record.")
@click.option("--profile", default=None, help="Sensor profile (default: $B2D_PROFILE or preview).")
@click.option("--episodes", default=None, type=int, help="Demonstrations per setting.")
@click.option("--eval-episodes", default=None, type=int, help="Rollouts per (setting, channel).")
@click.option("--max-steps", default=None, type=click.IntRange(min=1), help="Cap on control steps per episode.")
@click.option("--render-workers", default=None, type=click.IntRange(min=1),
              help="Processes rendering each episode (default: $B2D_RENDER_WORKERS or 1).")
@click.option("--train-steps", default=None, type=click.IntRange(min=1), help="Override the policy config's training steps.")
def materialize(settings_, all_settings, profile, episodes, eval_episodes, max_steps, render_workers, train_steps) -> None:
    """Materialize the whole asset chain (recordings -> episodes -> checkpoints -> rollouts -> table) with Dagster."""
    import dagster as dg

    from b2d_pipeline.chain import materialize_chain
    from b2d_pipeline.instance import ensure_instance_yaml
    from b2d_pipeline.partitions import recordable_setting_keys
    from b2d_pipeline.scale_out.instance_yaml import require_instance_services
    from b2d_pipeline.settings import FactorySettings, use_default_dagster_home

    overrides = {k: v for k, v in {"profile": profile, "demo_episodes": episodes, "eval_episodes": eval_episodes,
                                   "max_steps": max_steps, "render_workers": render_workers,
                                   "train_steps": train_steps}.items() if v is not None}
    settings = FactorySettings.from_env(**overrides)
    for key in settings_:
        registry.parse_setting_key(key)
        if key not in recordable_setting_keys():    # the others are recorded by a person (`b2d teleop`)
            raise UnknownNameError("recordable setting", key, recordable_setting_keys())
    home = use_default_dagster_home(settings.data_root)
    ensure_instance_yaml(home)
    require_instance_services(home)       # an instance on Postgres that is down: one line, how to start it
    with dg.DagsterInstance.get() as instance:
        chosen = recordable_setting_keys() if all_settings else (list(settings_) or [DEFAULT_SETTING])
        results = materialize_chain(settings, chosen, instance,
                                    log=lambda m: click.echo(m, err=True))
    table = settings.data_root / "evaluation" / "evaluation_table.parquet"
    if table.exists():
        import pandas as pd
        cols = ["task", "embodiment", "policy", "channel", "N", "SR", "LSCR"]
        click.echo(pd.read_parquet(table)[cols].to_string(index=False))
    sys.exit(0 if all(r.success for r in results) else 1)


cli.add_command(export)
export.add_command(lerobot_export_cmd)
cli.add_command(show)
cli.add_command(tactile)
cli.add_command(tasks)
cli.add_command(teleop)
cli.add_command(retarget)
cli.add_command(train)
cli.add_command(eval_cmd)
cli.add_command(tables)
cli.add_command(serve)
cli.add_command(layout)


if __name__ == "__main__":
    cli()
