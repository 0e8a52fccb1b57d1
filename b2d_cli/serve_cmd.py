"""`b2d serve`: serve a b2d checkpoint over the harness's TCP protocol or openpi's websocket protocol;
`b2d layout`: compute a fixed-width (32-slot) action/state layout from demonstrations."""

from __future__ import annotations

import signal
import sys
from pathlib import Path

import click


@click.command()
@click.option("--checkpoint", "checkpoint_dir", required=True, type=click.Path(path_type=Path))
@click.option("--protocol", type=click.Choice(["tcp", "ws"]), default="tcp", show_default=True,
              help="tcp: length-prefixed JSON (the evaluation harness); ws: openpi's msgpack websocket.")
@click.option("--port", default=8000, show_default=True, type=click.IntRange(0, 65535), help="0: any free port.")
@click.option("--host", default="127.0.0.1", show_default=True, help="Address to bind (loopback unless told otherwise).")
@click.option("--max-mb", default=64, show_default=True, type=click.IntRange(min=1),
              help="Refuse messages larger than this many MiB.")
@click.option("--layout", "layout_file", default=None, type=click.Path(path_type=Path),
              help="Speak a fixed-width layout on the wire (YAML from `b2d layout`); clients pick it up.")
def serve(checkpoint_dir, protocol, port, host, max_mb, layout_file) -> None:
    """Serve a checkpoint's policy until interrupted; `b2d eval --remote URL` evaluates it."""
    from policies.learned import LearnedPolicy
    from policies.remote import make_server, server_url
    from policies.remote.layout import load_layout

    policy = LearnedPolicy(checkpoint_dir)
    layout = load_layout(layout_file) if layout_file else None
    server = make_server(policy, protocol, host=host, port=port, max_bytes=max_mb * 1024 * 1024, layout=layout)
    # the first line names the URL (port 0 picks one), so scripts can read it
    click.echo(f"serving {policy.name} ({policy.checkpoint.task} on {policy.checkpoint.embodiment}) at "
               f"{server_url(protocol, server.address)}", err=True)
    sys.stderr.flush()
    _stop_on_signals()
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.close()


def _stop_on_signals() -> None:
    """SIGTERM (a process manager, Kubernetes, `kill`) and SIGINT stop the server cleanly. Set here because
    a parent may have left them ignored, and an ignored disposition survives exec: started from a
    process that ignores SIGTERM, the server would otherwise outlive every polite stop."""
    def stop(signum, frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)


@click.command()
@click.argument("episodes", nargs=-1, required=True, type=click.Path(exists=True, path_type=Path))
@click.option("--out", "out_file", required=True, type=click.Path(path_type=Path), help="The layout YAML to write.")
@click.option("--dim", default=32, show_default=True, type=click.IntRange(min=1), help="Slots of the policy head.")
def layout(episodes, out_file, dim) -> None:
    """Compute an embodiment's action/state layout for a fixed-width head from its demonstrations (HDF5
    episodes or folders of them): arm joints kept, hand joints reduced to synergies; prints the
    reconstruction error."""
    import json

    from policies.remote.layout import compute_layout, save_layout

    files = []
    for p in episodes:
        files.extend(sorted(p.glob("episode_*.hdf5")) if p.is_dir() else [p])
    if not files:
        raise click.UsageError("no episodes (episode_*.hdf5) in the given paths")
    result = compute_layout(files, dim)
    save_layout(result, out_file)
    click.echo(json.dumps({"layout": str(out_file), "embodiment": result.embodiment, "dim": dim,
                           "action": result.report["action"], "state": result.report["state"]}, indent=2))
