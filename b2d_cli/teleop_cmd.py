"""`b2d teleop`: a live teleoperation session writing raw recordings, driven from the keyboard, a
loopback control port or a script."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import click

from sim import registry

INPUT_HELP = ("Operator stream: recorded:PATH.npz, arkit:PORT, webcam:MODEL_PATH (optional extra) or manus:... "
              "Give two live inputs to merge them (keypoints from the first, wrist poses from the second).")


def default_out_dir(task: str, embodiment: str) -> Path:
    from b2d_pipeline.settings import REPO_ROOT

    root = Path(os.environ.get("B2D_DATA_ROOT", REPO_ROOT / "data"))
    return root / "teleop" / f"{task}__{embodiment}"


@click.command()
@click.option("--task", required=True)
@click.option("--embodiment", required=True)
@click.option("--input", "inputs", multiple=True, required=True, help=INPUT_HELP)
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Folder for the raw recordings [default: $B2D_DATA_ROOT/teleop/<task>__<embodiment>].")
@click.option("--control-port", type=click.IntRange(0, 65535), default=None,
              help="Also take commands on this TCP port, one per line (0 = any free port; printed).")
@click.option("--host", default="127.0.0.1", show_default=True,
              help="Interface for the control port and network inputs (the port has no authentication).")
@click.option("--script", default=None, help='Control script, e.g. "start;wait 2.0;save" (seconds of session time).')
@click.option("--control-file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Control script in a file: one command or 'wait SECONDS' per line, # comments.")
@click.option("--as-fast-as-possible", "fast", is_flag=True, help="Do not pace to the wall clock (recorded inputs).")
@click.option("--first-index", default=0, show_default=True, type=click.IntRange(min=0),
              help="First episode index (sets its seed); indices with a file in --out are skipped.")
@click.option("--max-steps", default=None, type=click.IntRange(min=1),
              help="Stop recording an episode after this many steps.")
@click.option("--stream-hz", default=None, type=click.FloatRange(min=0, min_open=True),
              help="The input's frame rate, for telling lost frames from a slow stream [default: from the file; "
                   "unknown for live inputs: every step without a frame is flagged].")
@click.option("--translation-scale", default=1.0, show_default=True, type=click.FloatRange(min=0, min_open=True),
              help="Robot wrist travel per metre of operator wrist travel.")
@click.option("--stop-on-success/--keep-recording-after-success", default=True, show_default=True,
              help="Stop recording at stable success (reach-and-stop, as b2d record).")
def teleop(task, embodiment, inputs, out_dir, control_port, host, script, control_file, fast, first_index,
           max_steps, stream_hz, translation_scale, stop_on_success) -> None:
    """Drive the robot live from an operator stream and record raw episodes.

    Controls: start (home, then record), save (write the raw recording, home), discard (drop it,
    home), home, status, quit. They come from the keyboard in a terminal (keys s w d h ? q), from
    --control-port (one command per line, one reply line each) or from --script / --control-file,
    whose waits are seconds of session time: a recorded stream with a script runs reproducibly.
    """
    from teleop.session import TeleopSession
    from teleop.session_control import (KEY_HELP, ControlPort, ControlScriptError, KeyboardControl, ScriptControl,
                                        parse_script, read_control_file)
    from teleop.session_inputs import InputError, open_input

    registry.validate_name("task", task)
    registry.validate_name("embodiment", embodiment)
    if script is not None and control_file is not None:
        raise click.UsageError("give --script or --control-file, not both")
    say = lambda message: click.echo(message, err=True)   # noqa: E731
    try:
        items = (parse_script(script) if script is not None
                 else read_control_file(control_file) if control_file is not None else None)
    except ControlScriptError as exc:
        raise click.UsageError(str(exc)) from None
    keyboard_fd = sys.stdin.fileno() if _stdin_is_terminal() else None
    if items is None and control_port is None and keyboard_fd is None:
        raise click.UsageError("nothing can control the session: give --script or --control-file, a --control-port, "
                               "or run it in a terminal (keyboard)")
    try:
        source = open_input(inputs, host=host, stream_hz=stream_hz)
    except InputError as exc:
        raise click.UsageError(str(exc)) from None
    controls, closers = [], [source.close]
    try:
        if fast and source.recorded is None:
            raise click.UsageError("--as-fast-as-possible needs a recorded input (a live device runs in real time)")
        say(f"input: {source.description}")
        session = TeleopSession(task, embodiment, source, out_dir or default_out_dir(task, embodiment),
                                first_index=first_index, max_steps=max_steps, stop_on_success=stop_on_success,
                                translation_scale=translation_scale, say=say)
        scripted = ScriptControl(items, say) if items is not None else None
        if scripted:
            controls.append(scripted)
        if control_port is not None:
            if host not in ("127.0.0.1", "localhost", "::1"):
                say(f"warning: the control port on {host} accepts commands from anyone who can reach it")
            port = ControlPort(host, control_port)
            closers.append(port.close)
            controls.append(port)
            h, p = port.address
            say(f"control port: tcp {h}:{p} (one command per line: start, save, discard, home, status, quit)")
        if keyboard_fd is not None:
            keyboard = KeyboardControl(keyboard_fd, say)
            closers.append(keyboard.close)
            controls.append(keyboard)
            say(f"keys: {KEY_HELP}")
        live = control_port is not None or keyboard_fd is not None
        until = None if live else scripted.done
        say(f"{task} on {embodiment}: output {session.out_dir}; next episode {session.episode_id}; "
            f"{'as fast as possible' if fast else 'real time'}")
        try:
            pacer = session.run(controls, realtime=not fast, until=until)
        except KeyboardInterrupt:
            pacer = None
            say("interrupted")
    finally:
        for close in reversed(closers):
            close()
    for e in session.saved:
        click.echo(f"{e.episode_id}  steps={e.steps:<5} {'success' if e.success else 'no success'}  "
                   f"flagged={e.flagged_steps:<4} {e.path}")
    if pacer is not None and pacer.enabled and pacer.late_steps:
        say(f"note: {pacer.late_steps} of {session.step_count} control steps ran slower than real time")
    refused = scripted.refused if scripted else []
    for r in refused:
        say(f"error: script command refused: {r}")
    if refused:
        sys.exit(1)


def _stdin_is_terminal() -> bool:
    try:
        return sys.stdin.isatty()
    except (AttributeError, ValueError):
        return False
