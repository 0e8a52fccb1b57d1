"""`b2d export lerobot`: HDF5 episodes as a LeRobot dataset (v2.1 or v3.0) with GR00T's modality.json."""

from __future__ import annotations

import sys
from pathlib import Path

import click

FORMAT_CHOICES = ("v2.1", "v3.0")   # lerobot_export.FORMATS, listed here so --help needs no PyAV import


@click.command("lerobot")
@click.argument("episodes", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--out", required=True, type=click.Path(path_type=Path), help="Dataset folder to write.")
@click.option("--format", "version", type=click.Choice(FORMAT_CHOICES), default="v2.1", show_default=True,
              help="v2.1: per-episode files (GR00T N1.5, openpi); v3.0: lerobot's current layout.")
@click.option("--views", default=None,
              help="Comma-separated camera ids to export [default: every view of the first episode].")
@click.option("--tactile/--no-tactile", default=True, show_default=True,
              help="Export each tactile site's TacMap as an image feature.")
@click.option("--crf", default=18, show_default=True, type=click.IntRange(0, 51),
              help="x264 constant quality of the MP4s (lower: larger files, closer to the stored frames).")
@click.option("--overwrite", is_flag=True, help="Replace --out if it exists and is not empty.")
def lerobot(episodes: tuple[Path, ...], out: Path, version: str, views: str | None, tactile: bool, crf: int,
            overwrite: bool) -> None:
    """Export EPISODES (HDF5 files or folders of them) to a LeRobot dataset folder.

    A bad episode is reported and skipped; the others are exported (exit code 1 if any was skipped)."""
    from lerobot_export import NothingExported, VideoSettings, export_lerobot

    chosen = tuple(v.strip() for v in views.split(",") if v.strip()) if views else None
    try:
        result = export_lerobot(list(episodes), out, version, views=chosen, tactile=tactile,
                                video=VideoSettings(crf=crf), overwrite=overwrite)
    except (FileExistsError, NothingExported) as exc:
        click.echo(f"error: {exc}", err=True)
        sys.exit(2 if isinstance(exc, FileExistsError) else 1)
    for path, message in result.errors.items():
        click.echo(f"error: {message if path in message else f'{path}: {message}'}", err=True)
    click.echo(str(result.path))
    click.echo(f"LeRobot {result.version}: {len(result.episodes)} episode(s), {result.frames} frames in "
               f"{result.seconds:.1f} s; {len(result.errors)} skipped", err=True)
    if result.errors:
        sys.exit(1)
