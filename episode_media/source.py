"""Open an episode for media output, choose its frames and rebuild its scene; every failure names
the file and the field."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from episodes import schema
from episodes.reader import EpisodeReader
from sim.errors import SpecError

@dataclass(frozen=True)
class FrameRange:
    """Frames start, start + stride, ... below stop (Python slice semantics)."""

    start: int
    stop: int
    stride: int = 1

    @property
    def indices(self) -> np.ndarray:
        return np.arange(self.start, self.stop, self.stride)

    def __len__(self) -> int:
        return len(range(self.start, self.stop, self.stride))


def frame_range(path: str | Path, num_frames: int, spec: str | None = None, stride: int = 1) -> FrameRange:
    """Parse "A:B" (either end may be left out) against an episode of `num_frames` frames."""
    if stride < 1:
        raise SpecError(path, "--stride", "an integer >= 1", stride)
    start, stop = 0, num_frames
    if spec:
        parts = spec.split(":")
        try:
            if len(parts) != 2:
                raise ValueError(spec)
            start = int(parts[0]) if parts[0].strip() else 0
            stop = int(parts[1]) if parts[1].strip() else num_frames
        except ValueError:
            raise SpecError(path, "--frames", "A:B with integers A < B (frames A to B-1)", spec) from None
    if not 0 <= start < stop <= num_frames:
        raise SpecError(path, "--frames", f"a non-empty range A:B with 0 <= A < B <= {num_frames} "
                                          f"(the episode has {num_frames} frames)", spec)
    return FrameRange(start, stop, stride)


def frame_rate_hz(reader: EpisodeReader, frames: FrameRange) -> float:
    """Playback rate of the chosen frames, from their timestamps (the profile's rate for one frame)."""
    if len(frames) >= 2 and "time/timestamp_ns" in reader:
        stamps = reader.read("time/timestamp_ns", frames.start, frames.stop)[:: frames.stride]
        step_ns = float(np.median(np.diff(stamps)))
        if step_ns > 0:
            return 1e9 / step_ns
    config = reader.meta("collection_config") if "meta/collection_config" in reader else None
    rate = config.get("profile", {}).get("rate_hz") if isinstance(config, dict) else None
    return float(rate) / frames.stride if rate else 1.0


class _EpisodeSceneFields:
    """What `sim.replay.scene_for` needs (task, embodiment, scene sample, actuators), from an episode."""

    def __init__(self, reader: EpisodeReader):
        for field in ("meta/task", "meta/embodiment", "meta/scene", "action/names"):
            if field not in reader:
                raise SpecError(reader.path, field, "a dataset (needed to rebuild the episode's scene)")
        self.task = reader.static("meta/task")
        self.embodiment = reader.static("meta/embodiment")
        self.scene_sample = reader.static("meta/scene")
        self.actuator_names = reader.static("action/names")
        config = reader.meta("collection_config") if "meta/collection_config" in reader else {}
        self.hand_model = config.get("hand_model", "generated") if isinstance(config, dict) else "generated"
        try:
            json.loads(self.scene_sample)
        except (TypeError, json.JSONDecodeError) as exc:
            raise SpecError(reader.path, "meta/scene", "the resolved scene sample as JSON") from exc


def episode_scene(reader: EpisodeReader):
    """The episode's compiled scene, rebuilt from its meta exactly as replay builds it."""
    from sim.replay import scene_for

    return scene_for(_EpisodeSceneFields(reader), reader.path)
