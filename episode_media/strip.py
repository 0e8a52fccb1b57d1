"""`b2d show`: each chosen frame of an episode as one labelled image - the cameras tiled at their
stored pixels, the tactile heatmaps (tactile.heatmap, when the episode has tactile) beside them and
a header with the frame index, time and success flag - written as an MP4 or a PNG strip."""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from episode_media.source import FrameRange, frame_range, frame_rate_hz
from episodes import schema
from episodes.atomic import atomic_path
from episodes.reader import EpisodeReader, open_episode
from sim.errors import SpecError
from tactile.heatmap import tacmap_panel

HEADER_PX = 28
LABEL_PX = 18
GAP_PX = 6
CAMERA_COLUMNS = 3
BACKGROUND = 255
FONT = cv2.FONT_HERSHEY_SIMPLEX
MP4_FOURCC = "mp4v"
MAX_STRIP_PIXELS = 1 << 28    # ~0.8 GB of RGB; longer strips need --frames / --stride (or an MP4)


def _label(image: np.ndarray, text: str, x: int, y: int, height: int, max_width: int) -> None:
    """Dark text fitted into the box of `height` x `max_width` whose top-left corner is (x, y)."""
    scale = 0.45 if height < HEADER_PX else 0.6
    (width, _), _ = cv2.getTextSize(text, FONT, scale, 1)
    if width > max_width > 0:
        scale *= max_width / width
    cv2.putText(image, text, (x + 2, y + height - 6), FONT, scale, (20, 20, 20), 1, cv2.LINE_AA)


def compose_frame(header: str, cameras: dict[str, np.ndarray], tactile_panel: np.ndarray | None = None,
                  columns: int = CAMERA_COLUMNS) -> np.ndarray:
    """One frame as RGB uint8: header on top, camera tiles (unscaled, labelled with their id) in a
    grid of `columns`, the tactile panel to their right. Width and height are even (video codecs)."""
    if not cameras:
        raise ValueError("compose_frame needs at least one camera image")
    h = max(img.shape[0] for img in cameras.values())
    w = max(img.shape[1] for img in cameras.values())
    columns = min(columns, len(cameras))
    rows = math.ceil(len(cameras) / columns)
    grid_w, grid_h = GAP_PX + columns * (w + GAP_PX), rows * (LABEL_PX + h + GAP_PX)
    panel_h, panel_w = tactile_panel.shape[:2] if tactile_panel is not None else (0, 0)
    width, height = grid_w + panel_w, HEADER_PX + max(grid_h, panel_h)
    canvas = np.full((height + height % 2, width + width % 2, 3), BACKGROUND, np.uint8)
    _label(canvas, header, GAP_PX, 0, HEADER_PX, canvas.shape[1] - 2 * GAP_PX)
    for i, (name, img) in enumerate(cameras.items()):
        x = GAP_PX + (i % columns) * (w + GAP_PX)
        y = HEADER_PX + (i // columns) * (LABEL_PX + h + GAP_PX)
        _label(canvas, name, x, y, LABEL_PX, w)
        canvas[y + LABEL_PX: y + LABEL_PX + img.shape[0], x: x + img.shape[1]] = img
    if tactile_panel is not None:
        canvas[HEADER_PX: HEADER_PX + panel_h, grid_w: grid_w + panel_w] = tactile_panel
    return canvas


@dataclass
class EpisodeFrames:
    """Reads and composes the chosen frames of an open episode, one at a time."""

    reader: EpisodeReader
    frames: FrameRange
    camera_scale: int = 1      # whole-pixel enlargement of camera tiles (1: the stored pixels)

    def __post_init__(self):
        r, path = self.reader, self.reader.path
        self.cameras = _camera_order(r)
        if not self.cameras:
            raise SpecError(path, "cameras", "at least one camera group with an rgb dataset")
        T = r.num_frames
        for cam in self.cameras:
            _check_per_frame(r, f"cameras/{cam}/rgb", T, "uint8 [T, H, W, 3] RGB images", rgb=True)
        for node in ("episode/success", "time/timestamp_ns", "frame_valid"):
            _check_per_frame(r, node, T, "one value per frame")
        self.sites = r.tactile_sites
        for site in self.sites:
            _check_per_frame(r, schema.tactile_path("tacmap", site), T, "uint8 [T, Ht, Wt] (listed in "
                                                                        "robot/tactile/site_names)")
        self.site_columns = _sites_per_row(r, self.sites)
        for node in ("meta/task", "meta/embodiment"):
            if node not in r:
                raise SpecError(path, node, "a string dataset (shown in the header)")
        self.title = f"{r.path.name}  {r.meta('task')} / {r.meta('embodiment')}"

    def image(self, k: int) -> np.ndarray:
        r = self.reader
        one = lambda node: r.read(node, k, k + 1)[0]  # noqa: E731 - only chunks of frame k are read
        cams = {cam: _enlarge(one(f"cameras/{cam}/rgb"), self.camera_scale) for cam in self.cameras}
        panel = None
        if self.sites:
            maps = {site: one(schema.tactile_path("tacmap", site)) for site in self.sites}
            panel = tacmap_panel(maps, title="tactile (TacMap)", columns=self.site_columns)
        header = (f"{self.title}  frame {k} of {r.num_frames}  t = {one('time/timestamp_ns') * 1e-9:.2f} s  "
                  f"success: {'yes' if one('episode/success') else 'no'}"
                  + ("" if one("frame_valid") else "  [frame invalid]"))
        return compose_frame(header, cams, panel)

    def __iter__(self) -> Iterator[np.ndarray]:
        for k in self.frames.indices:
            yield self.image(int(k))


def _enlarge(image: np.ndarray, scale: int) -> np.ndarray:
    return image if scale == 1 else cv2.resize(image, None, fx=scale, fy=scale, interpolation=cv2.INTER_NEAREST)


def _camera_order(reader: EpisodeReader) -> list[str]:
    """The profile's camera order (chest, overhead, ...) where recorded; other cameras after it."""
    present = [c for c in reader.camera_ids if f"cameras/{c}/rgb" in reader]
    config = reader.meta("collection_config") if "meta/collection_config" in reader else {}
    declared = config.get("profile", {}).get("cameras", {}).get("ids", []) if isinstance(config, dict) else []
    return [c for c in declared if c in present] + [c for c in present if c not in declared]


def _sites_per_row(reader: EpisodeReader, sites: list[str]) -> int:
    """One row of heatmaps per hand (left above right), as `b2d tactile show` lays them out."""
    if not sites:
        return 0
    meta = json.loads(reader.static(f"{schema.TACTILE_ROOT}/meta")) if f"{schema.TACTILE_ROOT}/meta" in reader else {}
    per_side = [sum(s.get("side") == side for s in meta.get("sites", [])) for side in ("left", "right")]
    return max(per_side) or min(5, len(sites))


def _check_per_frame(reader: EpisodeReader, node: str, frames: int, expected: str, rgb: bool = False) -> None:
    if node not in reader:
        raise SpecError(reader.path, node, f"a dataset: {expected}")
    first = reader.read(node, 0, 1)
    full = reader.read(node, frames - 1, frames + 1)     # one row past the end reads nothing if T rows
    if first.shape[0] != 1 or full.shape[0] != 1 or (rgb and (first.ndim != 4 or first.shape[-1] != 3
                                                              or first.dtype != np.uint8)):
        raise SpecError(reader.path, node, f"{expected} with T = {frames} (time/frame_index)",
                        f"{first.dtype} {first.shape[1:]}")


@dataclass(frozen=True)
class Shown:
    path: Path
    kind: str          # "mp4" | "png"
    frames: int
    fps: float
    note: str = ""


def default_out(episode: Path) -> Path:
    return Path(f"{episode.stem}.mp4")


def show_episode(episode: str | Path, out: str | Path | None = None, frames: str | None = None, stride: int = 1,
                 camera_scale: int = 1, fourcc: str = MP4_FOURCC) -> Shown:
    """Write the chosen frames as an MP4 (`fourcc`) or, for a .png path or when that codec cannot
    be opened, as a PNG strip (frames top to bottom)."""
    episode = Path(episode)
    out = Path(out) if out is not None else default_out(episode)
    if out.suffix.lower() not in (".mp4", ".png"):
        raise SpecError(out, "--out", "a path ending in .mp4 (video) or .png (strip)")
    with open_episode(episode) as reader:
        chosen = frame_range(episode, reader.num_frames, frames, stride)
        if camera_scale < 1:
            raise SpecError(episode, "--camera-scale", "an integer >= 1", camera_scale)
        images = EpisodeFrames(reader, chosen, camera_scale)
        fps = frame_rate_hz(reader, chosen)
        note = ""
        if out.suffix.lower() == ".mp4":
            if _write_mp4(images, out, fps, fourcc):
                return Shown(out, "mp4", len(chosen), fps)
            note = f"OpenCV cannot write '{fourcc}' video here; wrote a PNG strip instead"
            out = out.with_suffix(".png")
        _write_png_strip(images, out, episode)
    return Shown(out, "png", len(chosen), fps, note)


class _CodecUnavailable(Exception):
    pass


def _write_mp4(images: EpisodeFrames, out: Path, fps: float, fourcc: str) -> bool:
    """Stream frames into a video; False (and nothing written) when the codec cannot be opened."""
    frames = iter(images)
    first = next(frames)
    size = (first.shape[1], first.shape[0])
    try:
        with atomic_path(out, keep_suffix=True) as tmp:
            writer = cv2.VideoWriter(str(tmp), cv2.VideoWriter_fourcc(*fourcc), fps, size)
            if not writer.isOpened():
                raise _CodecUnavailable
            try:
                writer.write(cv2.cvtColor(first, cv2.COLOR_RGB2BGR))
                for image in frames:
                    assert image.shape == first.shape, "every frame has the first frame's layout"
                    writer.write(cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
            finally:
                writer.release()
    except _CodecUnavailable:
        return False
    return True


def _write_png_strip(images: EpisodeFrames, out: Path, episode: Path) -> None:
    frames = iter(images)
    first = next(frames)
    pixels = len(images.frames) * first.shape[0] * first.shape[1]
    if pixels > MAX_STRIP_PIXELS:
        raise SpecError(episode, "--frames", f"a strip of at most {MAX_STRIP_PIXELS} pixels (choose fewer frames "
                                             f"with --frames / --stride, or write an .mp4)",
                        f"{len(images.frames)} frames of {first.shape[1]}x{first.shape[0]}")
    strip = np.concatenate([first, *frames], axis=0)
    ok, png = cv2.imencode(".png", cv2.cvtColor(strip, cv2.COLOR_RGB2BGR))
    if not ok:
        raise SpecError(out, "--out", "a strip OpenCV can encode as PNG")
    with atomic_path(out, keep_suffix=True) as tmp:
        tmp.write_bytes(png.tobytes())
