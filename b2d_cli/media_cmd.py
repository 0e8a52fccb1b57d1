"""`b2d export usd` and `b2d show`: an episode's motion as USD, its cameras and tactile as a video."""

from __future__ import annotations

from pathlib import Path

import click


def frame_selection(command):
    """The episode argument and the --frames / --stride options both media commands take."""
    command = click.option("--stride", default=1, show_default=True, type=click.IntRange(min=1),
                           help="Keep every K-th frame.")(command)
    command = click.option("--frames", default=None,
                           help="Frames A:B (A to B-1, 0-based; either end may be left out) [default: all].")(command)
    return click.argument("episode", type=click.Path(path_type=Path))(command)


@click.group()
def export() -> None:
    """Export HDF5 episodes to other formats."""


@export.command()
@frame_selection
@click.option("--out", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Folder to write (frames/<episode>.usdc + assets/) [default: ./<episode>_usd].")
@click.option("--format", "file_format", type=click.Choice(["usdc", "usda"]), default="usdc", show_default=True)
def usd(episode: Path, out: Path | None, frames: str | None, stride: int, file_format: str) -> None:
    """Write the episode's motion as an animated USD stage (MuJoCo's USD exporter)."""
    from episode_media.usd_export import export_usd

    result = export_usd(episode, out, frames, stride, file_format)
    click.echo(str(result.path))
    click.echo(f"{result.frames} frames at {result.fps:g} fps: setup {result.setup_s:.2f} s, "
               f"{result.ms_per_frame:.1f} ms per later frame, save {result.save_s:.2f} s", err=True)


@click.command()
@frame_selection
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="An .mp4 video or a .png strip (frames top to bottom) [default: ./<episode>.mp4].")
@click.option("--camera-scale", default=1, show_default=True, type=click.IntRange(min=1),
              help="Enlarge camera tiles by this whole factor (1 shows the stored pixels).")
def show(episode: Path, out: Path | None, frames: str | None, stride: int, camera_scale: int) -> None:
    """Write the episode's cameras, tactile heatmaps beside them, per frame as an MP4 or a PNG strip."""
    from episode_media.strip import show_episode

    shown = show_episode(episode, out, frames, stride, camera_scale)
    if shown.note:
        click.echo(f"note: {shown.note}", err=True)
    click.echo(str(shown.path))
    click.echo(f"wrote {'an MP4' if shown.kind == 'mp4' else 'a PNG strip'} of {shown.frames} "
               f"frame{'s' if shown.frames != 1 else ''}"
               + (f" at {shown.fps:g} fps" if shown.kind == "mp4" else ""), err=True)
