"""What the per-partition asset checks look at beyond the schema: the rendered frames themselves and the
replays' fidelity. Plain functions over files (the Dagster layer only reports what they find).

A frame is invalid when its depth is not a finite, non-negative distance, or when its RGB image is
one flat colour (a render that drew nothing: a lost GL context or a camera inside a wall). Frames are
read a chunk of CHUNK_FRAMES at a time, so a paper-size episode is not held in memory whole.
"""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np

from episodes.reader import open_episode

CHUNK_FRAMES = 64
MAX_LISTED = 5          # frames named per problem; the count says how many more


def _frames(indices: np.ndarray) -> str:
    shown = ", ".join(map(str, indices[:MAX_LISTED].tolist()))
    more = f" and {len(indices) - MAX_LISTED} more" if len(indices) > MAX_LISTED else ""
    return f"frames {shown}{more}"


def frame_problems(path: str | Path) -> list[str]:
    """`<camera>/<dataset>: what` for every camera of an episode whose frames are not valid images."""
    problems: list[str] = []
    with open_episode(path) as reader:
        total = reader.num_frames
        for camera in reader.camera_ids:
            blank, bad_depth = [], []
            for start in range(0, total, CHUNK_FRAMES):
                stop = min(start + CHUNK_FRAMES, total)
                if f"cameras/{camera}/rgb" in reader:
                    rgb = reader.read(f"cameras/{camera}/rgb", start, stop).reshape(stop - start, -1)
                    blank.extend(start + np.flatnonzero((rgb == rgb[:, :1]).all(axis=1)))
                if f"cameras/{camera}/depth_m" in reader:
                    depth = reader.read(f"cameras/{camera}/depth_m", start, stop).reshape(stop - start, -1)
                    bad_depth.extend(start + np.flatnonzero(~(np.isfinite(depth) & (depth >= 0)).all(axis=1)))
            if blank:
                problems.append(f"cameras/{camera}/rgb: one flat colour (nothing drawn) on {_frames(np.array(blank))}")
            if bad_depth:
                problems.append(f"cameras/{camera}/depth_m: NaN, infinite or negative depth on "
                                f"{_frames(np.array(bad_depth))}")
    return problems


def replay_fidelity(path: str | Path) -> dict:
    """The fidelity a replay file recorded (sim/replay.py): drifts, the bound and frames over it."""
    with h5py.File(path, "r") as f:
        return json.loads(f.attrs["fidelity"])
