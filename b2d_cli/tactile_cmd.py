"""`b2d tactile show`: one frame's tacmaps as a heatmap panel, like the paper's tactile figures."""

from __future__ import annotations

import json
from pathlib import Path

import click

from episodes import schema
from sim.errors import SpecError


@click.group()
def tactile() -> None:
    """Look at the tactile data of HDF5 episodes."""


def frame_tacmaps(path: Path, frame: int) -> tuple[dict, str, int]:
    """({site: uint8 tacmap}, title, sites per row) of one frame; SpecError names the file and field."""
    from episodes.reader import open_episode

    with open_episode(path) as reader:
        sites = reader.tactile_sites
        if not sites:
            raise SpecError(path, schema.TACTILE_ROOT, "tactile frames (this episode was written without tactile)")
        try:
            frames = reader.num_frames
        except KeyError as exc:
            raise SpecError(path, "time/frame_index", "a dataset (not a b2d episode?)") from exc
        if not 0 <= frame < frames:
            raise SpecError(path, "--frame", f"a frame index in [0, {frames - 1}]", frame)
        maps = {}
        for site in sites:
            key = schema.tactile_path("tacmap", site)
            if key not in reader:
                raise SpecError(path, key, "a uint8 dataset [T, Ht, Wt] (listed in robot/tactile/site_names)")
            maps[site] = reader.read(key, frame, frame + 1)[0]
        seconds = reader.read("time/timestamp_ns", frame, frame + 1)[0] * 1e-9
        meta = json.loads(reader.static(f"{schema.TACTILE_ROOT}/meta"))
        per_side = [sum(s.get("side") == side for s in meta.get("sites", [])) for side in ("left", "right")]
        title = (f"{reader.meta('task')} / {reader.meta('embodiment')} - {path.name} - "
                 f"frame {frame} of {frames} (t = {seconds:.2f} s)")
    return maps, title, max(per_side) or min(5, len(sites))


@tactile.command()
@click.argument("episode", type=click.Path(path_type=Path))
@click.option("--frame", required=True, type=int, help="Frame index (0-based, as in time/frame_index).")
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="PNG to write [default: ./<episode>_tactile_<frame>.png].")
def show(episode: Path, frame: int, out: Path | None) -> None:
    """Write one frame's tacmaps as a PNG: a heatmap per site, one row per hand (left on top)."""
    import cv2

    from episodes.atomic import atomic_path
    from tactile.heatmap import tacmap_panel

    maps, title, columns = frame_tacmaps(episode, frame)
    panel = tacmap_panel(maps, title=title, columns=columns)
    ok, png = cv2.imencode(".png", cv2.cvtColor(panel, cv2.COLOR_RGB2BGR))
    if not ok:
        raise SpecError(episode, "--out", "a panel OpenCV can encode as PNG")
    out = out or Path(f"{episode.stem}_tactile_{frame:05d}.png")
    with atomic_path(out) as tmp:
        Path(tmp).write_bytes(png.tobytes())
    click.echo(str(out))

