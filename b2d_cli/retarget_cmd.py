"""`b2d retarget`: replay recorded operator streams onto another embodiment and score the result."""

from __future__ import annotations

from functools import partial
from pathlib import Path

import click

from b2d_cli import errors as cli_errors
from sim import registry


@click.command()
@click.argument("raw", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--embodiment", required=True, help="The embodiment to replay the demonstrations onto.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Folder for the new raw recordings [default: <RAW's folder>/retarget/<embodiment>].")
@click.option("--seed", type=int, default=None,
              help="Build the scene from this seed's demonstration sample [default: the recording's own sample].")
@click.option("--hold-steps", default=60, show_default=True, type=click.IntRange(min=0),
              help="Control steps the operator holds still after the stream ends (its last frame again).")
@click.option("--wrist", type=click.Choice(["session", "world"]), default="session", show_default=True,
              help="session: wrist motion relative to the first pose, from this embodiment's home (as a live "
                   "session); world: the hand base follows the recorded hand base's path in the world.")
@click.option("--max-steps", default=None, type=click.IntRange(min=1), help="Cap each episode's control steps.")
@click.option("--stop-on-success/--keep-recording-after-success", default=True, show_default=True,
              help="Stop at stable success (reach-and-stop, as b2d record).")
def retarget(raw, embodiment, out_dir, seed, hold_steps, wrist, max_steps, stop_on_success) -> None:
    """Replay the operator stream of raw recordings (keypoints and wrist poses, as `b2d record
    --operator stream` and `b2d teleop` keep them) through another embodiment's retargeting and arm
    IK, record new raw recordings and print the evaluator's verdict: success, stages, steps."""
    from episodes.atomic import clean_stale_temporaries
    from teleop.retarget_demo import retarget_file

    registry.validate_name("embodiment", embodiment)
    if out_dir is not None:
        clean_stale_temporaries(out_dir)
    run = partial(retarget_file, embodiment=embodiment, out_dir=out_dir, seed=seed, hold_steps=hold_steps,
                  max_steps=max_steps, stop_on_success=stop_on_success, wrist=wrist)
    if len(raw) == 1:        # one recording: its error is the command's, one line (b2d_cli/main.py)
        click.echo(run(raw[0]).summary())
        return
    failed, succeeded = [], 0
    for path in raw:
        try:
            result = run(path)
        except Exception as exc:      # one bad recording never stops the others
            if cli_errors.show_traceback():
                raise
            failed.append((path, exc))
            click.echo(f"error: {cli_errors.one_line(exc, path)}", err=True)
            continue
        succeeded += result.success
        click.echo(result.summary())
    click.echo(f"{succeeded} of {len(raw) - len(failed)} retargeted recordings succeed on {embodiment}", err=True)
    cli_errors.report_batch("recordings", len(raw), failed)
