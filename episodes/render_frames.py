"""One rendered frame under a sensor profile, from a posed state: every camera's images and
extrinsics, then tactile from the same pose (paper: one synchronized pass).

The render stage and `b2d bench replay` both use this class, so the benchmark measures exactly
the work the stage does. A modality that fails on a frame is stored blank and named in the frame's
error text instead of aborting the episode.
"""

from __future__ import annotations

import time
from collections import defaultdict

import mujoco
import numpy as np

from episodes import schema
from episodes.label_frames import LabelFrames
from episodes.tactile_frames import TactileFrames
from sim.registry import SensorProfile
from sim.render import CameraRig


class FrameRenderer:
    """``static()`` once per file, then ``capture(data)`` -> (datasets, error text) per posed frame."""

    def __init__(self, scene, profile: SensorProfile):
        self.profile = profile
        listed = any(m in profile.modalities for m in schema.LABEL_MODALITIES)
        self.labels = LabelFrames(scene, profile) if listed else None   # RGB-D-only profiles skip label setup
        self.cameras = CameraRig(scene.model, profile, segments=bool(self.labels and self.labels.needs_segmentation))
        self.tactile = TactileFrames(scene, profile) if profile.tactile_enabled else None
        self._seconds: dict[str, float] = defaultdict(float)

    def static(self) -> dict:
        p = self.profile
        out: dict = {f"cameras/{cam}/intrinsic": K for cam, K in self.cameras.intrinsics().items()}
        for cam in p.camera_ids:
            out[f"cameras/{cam}/camera_model"] = schema.CAMERA_MODEL
            out[f"cameras/{cam}/depth_semantics"] = schema.DEPTH_SEMANTICS
            out[f"cameras/{cam}/clip_range_m"] = np.array([p.clip_near_m, p.clip_far_m])
        if self.tactile is not None:
            out.update(self.tactile.static())
        if self.labels is not None:
            out.update(self.labels.static())
        return out

    def capture(self, data: mujoco.MjData) -> tuple[dict, str]:
        frame, errors = {}, []
        try:
            shots = self.cameras.capture(data)
        except Exception as exc:   # keep the episode: flag the frame instead of aborting
            errors.append(f"render failed: {exc}")
            shots = self._blank_shots()
        segments = {cam: shot.pop("segments") for cam, shot in shots.items() if "segments" in shot}
        for cam, T in self.cameras.extrinsics(data).items():
            frame[f"cameras/{cam}/extrinsic_world_from_cam"] = T
            for key, img in shots[cam].items():
                frame[f"cameras/{cam}/{key}"] = img
        if self.labels is not None:
            t0 = time.perf_counter()
            labels, label_error = self.labels.capture(data, segments)
            self._seconds["labels"] += time.perf_counter() - t0
            frame.update(labels)
            if label_error:
                errors.append(label_error)
        if self.tactile is not None:
            t0 = time.perf_counter()
            touch, touch_error = self.tactile.capture(data)
            self._seconds["tactile"] += time.perf_counter() - t0
            frame.update(touch)
            if touch_error:
                errors.append(touch_error)
        return frame, "; ".join(errors)

    def seconds(self) -> dict[str, float]:
        """Time spent so far per part: camera_scene_update, camera_rgb, camera_depth_and_ids (GL render and
        read-back), camera_decode (buffers -> metric depth and geom ids), labels_segmentation (masks),
        labels_box2d, labels_box3d, labels_occupancy, labels_other (the rest of the labels' time: laying
        out their datasets), tactile."""
        out = {**{f"camera_{k}": v for k, v in self.cameras.seconds.items()}, **self._seconds}
        if self.labels is not None:
            total = out.pop("labels", 0.0)
            parts = {f"labels_{k}": v for k, v in self.labels.seconds.items()}
            out.update(parts, labels_other=max(0.0, total - sum(parts.values())))
        return out

    def _blank_shots(self) -> dict:
        h, w = self.profile.height, self.profile.width
        blank = {}
        if self.cameras.want_rgb:
            blank["rgb"] = np.zeros((h, w, 3), np.uint8)
        if self.cameras.want_depth:
            blank["depth_m"] = np.zeros((h, w), np.float32)
        return {cam: dict(blank) for cam in self.profile.camera_ids}

    def close(self) -> None:
        self.cameras.close()
