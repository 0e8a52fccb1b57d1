"""Render the calibrated cameras of a scene: RGB, metric depth, intrinsics and extrinsics.

Rendering works from positions alone (`mj_kinematics` + `mj_camlight`), so a changed sensor
profile re-renders stored replay states without re-simulating. One renderer serves all cameras;
shadows and reflections stay off unless the profile asks (they cost ~5x per frame).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from sim.registry import SensorProfile  # noqa: E402

# MuJoCo cameras look along -z with +y up; the stored convention is OpenCV (x right, y down, z forward).
MJ_TO_CV = np.diag([1.0, -1.0, -1.0])


def intrinsic_matrix(fovy_deg: float, width: int, height: int) -> np.ndarray:
    fy = (height / 2.0) / np.tan(np.deg2rad(fovy_deg) / 2.0)
    return np.array([[fy, 0.0, width / 2.0], [0.0, fy, height / 2.0], [0.0, 0.0, 1.0]])


class CameraRig:
    def __init__(self, model: mujoco.MjModel, profile: SensorProfile):
        self.model = model
        self.profile = profile
        self.camera_ids = {name: model.camera(name).id for name in profile.camera_ids}
        model.vis.map.znear = profile.clip_near_m / max(model.stat.extent, 1e-6)
        model.vis.map.zfar = profile.clip_far_m / max(model.stat.extent, 1e-6)
        self.renderer = mujoco.Renderer(model, height=profile.height, width=profile.width)
        self._option = mujoco.MjvOption()
        self.want_rgb = "rgb" in profile.modalities
        self.want_depth = "depth" in profile.modalities

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
        """{camera: {"rgb": HxWx3 uint8, "depth_m": HxW float32}} at the current state."""
        frames: dict[str, dict[str, np.ndarray]] = {}
        shadows = self.profile.shadows
        for name, cid in self.camera_ids.items():
            self.renderer.update_scene(data, camera=cid, scene_option=self._option)
            flags = self.renderer.scene.flags
            flags[mujoco.mjtRndFlag.mjRND_SHADOW] = shadows
            flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = shadows
            out = {}
            if self.want_rgb:
                out["rgb"] = self.renderer.render().copy()
            if self.want_depth:
                self.renderer.enable_depth_rendering()
                out["depth_m"] = self.renderer.render().astype(np.float32, copy=True)
                self.renderer.disable_depth_rendering()
            frames[name] = out
        return frames

    def close(self) -> None:
        self.renderer.close()


def set_positions(model: mujoco.MjModel, data: mujoco.MjData, qpos: np.ndarray) -> None:
    """Pose the scene from stored positions: kinematics and camera/light placement only."""
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)
