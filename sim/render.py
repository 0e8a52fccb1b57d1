"""Render the calibrated cameras of a scene: RGB, metric depth, geom ids, intrinsics and extrinsics.

Rendering works from positions alone (`mj_kinematics` + `mj_camlight`), so a changed sensor
profile re-renders stored replay states without re-simulating. One renderer serves all cameras;
shadows and reflections, and multisample anti-aliasing, stay off unless the profile asks (`shadows`,
`antialias`: they cost ~5x and ~2.8x per RGB frame). Depth and geom ids come from one shared pass
(`sim.offscreen`), rendered before the RGB pass, which then draws only the geoms that own a pixel.
"""

from __future__ import annotations

import os
import time
from collections import defaultdict

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from sim.offscreen import OffscreenRenderer  # noqa: E402
from sim.registry import SensorProfile  # noqa: E402

# MuJoCo cameras look along -z with +y up; the stored convention is OpenCV (x right, y down, z forward).
MJ_TO_CV = np.diag([1.0, -1.0, -1.0])


def intrinsic_matrix(fovy_deg: float, width: int, height: int) -> np.ndarray:
    fy = (height / 2.0) / np.tan(np.deg2rad(fovy_deg) / 2.0)
    return np.array([[fy, 0.0, width / 2.0], [0.0, fy, height / 2.0], [0.0, 0.0, 1.0]])


def apply_antialias(model: mujoco.MjModel, profile: SensorProfile) -> None:
    """MuJoCo's default 4x multisampling is opt-in (`cameras.antialias`): it nearly triples the RGB
    render and slows the id pass, whose depth and ids it leaves unchanged."""
    model.vis.quality.offsamples = 4 if profile.antialias else 0


MUJOCO_TESSELLATION = (28, 16)     # MuJoCo's default (slices, stacks); no b2d model sets its own


def apply_tessellation(model: mujoco.MjModel, profile: SensorProfile) -> None:
    """The profile's primitive tessellation, read when the renderer's GL context is made (set either way:
    an earlier rig on the same model must not leave its own)."""
    model.vis.quality.numslices, model.vis.quality.numstacks = profile.tessellation or MUJOCO_TESSELLATION


class CameraRig:
    """`capture(data)` renders every camera of the profile. With `segments=True` each shot also
    holds "segments" (`sim.offscreen.SegmentIds`: geom per pixel): the segmentation that labels are
    made from."""

    def __init__(self, model: mujoco.MjModel, profile: SensorProfile, segments: bool = False,
                 still_layers: bool = True):
        self.model = model
        self.profile = profile
        self.camera_ids = {name: model.camera(name).id for name in profile.camera_ids}
        model.vis.map.znear = profile.clip_near_m / max(model.stat.extent, 1e-6)
        model.vis.map.zfar = profile.clip_far_m / max(model.stat.extent, 1e-6)
        apply_antialias(model, profile)
        apply_tessellation(model, profile)
        self.renderer = OffscreenRenderer(model, profile.width, profile.height, still_layers=still_layers,
                                          shadows=profile.shadows)
        self.want_rgb = "rgb" in profile.modalities
        self.want_depth = "depth" in profile.modalities
        self.want_segments = segments
        self.seconds: dict[str, float] = defaultdict(float)   # render time per modality (benchmarks)

    def intrinsics(self) -> dict[str, np.ndarray]:
        p = self.profile
        return {n: intrinsic_matrix(float(self.model.cam_fovy[i]), p.width, p.height)
                for n, i in self.camera_ids.items()}

    def extrinsics(self, data: mujoco.MjData) -> dict[str, np.ndarray]:
        """World-from-camera 4x4 transforms (OpenCV camera frame) at the current state."""
        out = {}
        for name, cid in self.camera_ids.items():
            T = np.eye(4)
            T[:3, :3] = data.cam_xmat[cid].reshape(3, 3) @ MJ_TO_CV
            T[:3, 3] = data.cam_xpos[cid]
            out[name] = T
        return out

    def capture(self, data: mujoco.MjData) -> dict[str, dict[str, np.ndarray]]:
        """{camera: {"rgb": HxWx3 uint8, "depth_m": HxW float32[, "segments": SegmentIds]}}."""
        frames: dict[str, dict[str, np.ndarray]] = {}
        clock = time.perf_counter
        for name, cid in self.camera_ids.items():
            t0 = clock()
            self.renderer.update(data, cid)
            out = {}
            t1 = clock()
            self.seconds["scene_update"] += t1 - t0
            if self.want_depth or self.want_segments:
                # the id pass first: the colour pass then draws only the geoms that own a pixel of it
                buffers = self.renderer.id_pass(self.want_segments)
                t0, t1 = t1, clock()
                self.seconds["depth_and_ids"] += t1 - t0
                depth, segments = self.renderer.decode(*buffers)   # buffers -> metric depth, segments: CPU work
                if self.want_depth:
                    out["depth_m"] = depth
                if segments is not None:
                    out["segments"] = segments
                t0, t1 = t1, clock()
                self.seconds["decode"] += t1 - t0
            if self.want_rgb:
                out = {"rgb": self.renderer.color(), **out}
                t0, t1 = t1, clock()
                self.seconds["rgb"] += t1 - t0
            frames[name] = out
        return frames

    def close(self) -> None:
        self.renderer.close()


def set_positions(model: mujoco.MjModel, data: mujoco.MjData, qpos: np.ndarray) -> None:
    """Pose the scene from stored positions: kinematics and camera/light placement only."""
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)
