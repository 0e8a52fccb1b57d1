"""What one HDF5 episode offers an export (its layout), checked before any frame is written.

Every episode of a LeRobot dataset shares one set of features, so the first good episode fixes the
layout and each later one must match it; a mismatch names the file, the HDF5 field and the value the
dataset expects."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from episodes import schema
from episodes.reader import EpisodeReader
from sim.errors import SpecError


@dataclass(frozen=True)
class Layout:
    fps: int
    robot_type: str
    state_names: tuple[str, ...]
    action_names: tuple[str, ...]
    views: tuple[tuple[str, int, int], ...]       # (camera id, height, width)
    tactile: tuple[tuple[str, int, int], ...]     # (site, height, width)
    tactile_encoding: str                          # robot/tactile/meta's "encoding" block as JSON ("" if none)
    source: str = ""                               # the episode that fixed the layout (for messages)

    def differences(self, other: "Layout") -> list[tuple[str, object, object]]:
        """(HDF5 field, expected, got) for each way `other` breaks this layout."""
        fields = (("meta/collection_config.profile.rate_hz", "fps"), ("meta/embodiment", "robot_type"),
                  ("robot/joint_names", "state_names"), ("action/names", "action_names"),
                  ("cameras/*/rgb", "views"), ("robot/tactile/site_names", "tactile"),
                  ("robot/tactile/meta.encoding", "tactile_encoding"))
        return [(field, getattr(self, attr), getattr(other, attr)) for field, attr in fields
                if getattr(self, attr) != getattr(other, attr)]


def _names(reader: EpisodeReader, path: str) -> tuple[str, ...]:
    if path not in reader:
        raise SpecError(reader.path, path, "a list of names")
    return tuple(reader.static(path))


def _fps(reader: EpisodeReader) -> int:
    """The frame rate, from the collection profile, checked against the stored frame times."""
    try:
        rate = float(reader.meta("collection_config")["profile"]["rate_hz"])
    except (KeyError, TypeError) as exc:
        raise SpecError(reader.path, "meta/collection_config", "JSON with profile.rate_hz") from exc
    if rate <= 0 or rate != int(rate):
        raise SpecError(reader.path, "meta/collection_config.profile.rate_hz",
                        "a whole number of frames per second (LeRobot stores fps as an integer)", rate)
    fps = int(rate)
    stamps = reader.read("time/timestamp_ns")
    if len(stamps) > 1 and np.abs(np.diff(stamps) - 1e9 / fps).max() > 1e3:
        raise SpecError(reader.path, "time/timestamp_ns", f"frames every {1e3 / fps:g} ms ({fps} Hz)",
                        f"steps of {np.unique(np.diff(stamps))[:5].tolist()} ns")
    return fps


def _per_frame(reader: EpisodeReader, path: str, trailing: tuple | None, frames: int, uint8: bool = False) -> tuple:
    if path not in reader:
        raise SpecError(reader.path, path, "a per-frame dataset")
    dataset = reader._file[path]     # EpisodeReader has no shape accessor; reading would load the frames
    shape = dataset.shape
    if shape[0] != frames or (trailing is not None and tuple(shape[1:]) != trailing):
        want = ("T",) + (trailing if trailing is not None else ("...",))
        raise SpecError(reader.path, path, f"shape {want} with T = {frames}", tuple(shape))
    if uint8 and dataset.dtype != "uint8":
        raise SpecError(reader.path, path, "uint8 images", str(dataset.dtype))
    return tuple(shape[1:])


def read_layout(reader: EpisodeReader, views: tuple[str, ...] | None, tactile: bool) -> Layout:
    """The episode's layout for the chosen camera views (None: all it has) and tactile on/off."""
    frames = reader.num_frames
    if frames == 0:
        raise SpecError(reader.path, "time/frame_index", "at least one frame", 0)
    state = _names(reader, "robot/joint_names")
    action = _names(reader, "action/names")
    for path in ("robot/qpos", "robot/qvel", "robot/qeffort"):
        _per_frame(reader, path, (len(state),), frames)
    _per_frame(reader, "action/action", (len(action),), frames)
    for path in ("episode/done", "episode/success"):
        _per_frame(reader, path, (), frames)
    wanted = tuple(reader.camera_ids) if views is None else views
    cams = []
    for cam in wanted:
        path = f"cameras/{cam}/rgb"
        if path not in reader:
            have = [c for c in reader.camera_ids if f"cameras/{c}/rgb" in reader]
            raise SpecError(reader.path, path,
                            f"RGB frames of view '{cam}' (the episode has: {', '.join(have) or 'none'})")
        dims = _per_frame(reader, path, None, frames, uint8=True)
        if len(dims) != 3 or dims[2] != 3 or dims[0] % 2 or dims[1] % 2:   # yuv420p halves chroma: even sides
            raise SpecError(reader.path, path, "[T, H, W, 3] uint8 with even H and W", (frames, *dims))
        cams.append((cam, dims[0], dims[1]))
    sites, encoding = [], ""
    if tactile and reader.tactile_sites:
        meta = json.loads(reader.static(f"{schema.TACTILE_ROOT}/meta"))
        encoding = json.dumps(meta.get("encoding", {}), sort_keys=True)
        for site in reader.tactile_sites:
            path = schema.tactile_path("tacmap", site)
            dims = _per_frame(reader, path, None, frames, uint8=True)
            if len(dims) != 2:
                raise SpecError(reader.path, path, "[T, Ht, Wt] uint8 TacMaps", (frames, *dims))
            sites.append((site, *dims))
    return Layout(fps=_fps(reader), robot_type=str(reader.meta("embodiment")), state_names=state,
                  action_names=action, views=tuple(cams), tactile=tuple(sites), tactile_encoding=encoding,
                  source=str(reader.path))


def check_matches(layout: Layout, reader: EpisodeReader) -> None:
    """SpecError unless the episode offers exactly the dataset's layout."""
    mine = read_layout(reader, tuple(v for v, _, _ in layout.views), bool(layout.tactile))
    for field, expected, got in layout.differences(mine):
        raise SpecError(reader.path, field, f"{expected!r} (as in {Path(layout.source).name}, "
                                            "which fixed this dataset's features)", got)
