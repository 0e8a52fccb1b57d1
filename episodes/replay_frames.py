"""The frames of one replay under one sensor profile, rendered one at a time by index.

The render stage's writing process and its helper processes (episodes/render_pool.py) both render
through this class, so a frame is made the same way wherever it is made: posed from the stored
positions alone (kinematics and camera placement), which makes each frame independent of the ones
rendered before it in the same process.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import h5py
import mujoco
import numpy as np

from episodes.render_frames import FrameRenderer
from sim.registry import SensorProfile
from sim.render import set_positions
from sim.replay import scene_for


class RawView:
    """The fields of a raw recording that `scene_for` needs, read from a replay file."""

    def __init__(self, f: h5py.File):
        self.task = f.attrs["task"]
        self.embodiment = f.attrs["embodiment"]
        self.scene_sample = f.attrs["scene_sample"]
        self.actuator_names = json.loads(f.attrs["actuator_names"])
        self.hand_model = str(f.attrs.get("hand_model", "generated"))


class ReplayFrames:
    """``capture(i)`` -> (datasets of frame i, whether it has an error) for the control steps `steps`;
    ``close()`` frees the renderer."""

    def __init__(self, replay_path: Path, profile: SensorProfile, steps: np.ndarray):
        self.steps = np.asarray(steps)
        with h5py.File(replay_path, "r") as src:
            scene = scene_for(RawView(src), replay_path)
            self._qpos = src["qpos"][int(self.steps[0]): int(self.steps[-1]) + 1]
        self.model = scene.model
        self.data = mujoco.MjData(self.model)
        self.renderer = FrameRenderer(scene, profile)
        self.pose_s = 0.0

    def static(self) -> dict:
        return {**self.renderer.static(), "render/frame_steps": self.steps}

    def capture(self, i: int) -> tuple[dict, bool]:
        t0 = time.perf_counter()
        set_positions(self.model, self.data, self._qpos[self.steps[i] - self.steps[0]])
        self.pose_s += time.perf_counter() - t0
        frame, error = self.renderer.capture(self.data)
        frame["render/frame_errors"] = error
        return frame, bool(error)

    def seconds(self) -> dict[str, float]:
        return {"pose": self.pose_s, **self.renderer.seconds()}

    def close(self) -> None:
        self.renderer.close()
