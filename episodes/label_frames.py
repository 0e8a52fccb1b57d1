"""Label frames of a render, in the episode layout (`schema.LABEL_MODALITIES` and their nodes).

The render stage poses the scene for each frame, renders every camera (with the geom-id image when
`needs_segmentation`), and asks this module for that frame's label datasets: per-camera
semantic / instance masks and 2D boxes, per-object 3D boxes, the occupancy grid. Only the modalities
the profile lists are produced. A label that cannot be computed for a frame is stored blank (masks 0,
boxes NaN with visibility 0, empty grid with frame_valid false) and named in the error text, like a
failed camera frame, instead of aborting the episode.

Layout: the paper's labels/box2d/{camera_id}/{obj_id}/, labels/box3d/{obj_id}/ and
labels/occupancy_tsdf/; semantic and instance segmentation (cameras/{camera_id}/semantic_seg and
instance_seg, [T, H, W]), the id maps stored once as JSON (labels/semantic_classes, labels/instances)
and labels/occupancy_tsdf/instance_grid are b2d additions to the paper's table.
"""

from __future__ import annotations

import json
import logging
import time
from collections import defaultdict
from typing import Mapping

import mujoco
import numpy as np

from episodes import schema
from sim.labels.box2d import Box2DLabeler
from sim.labels.box3d import Box3DLabeler, Boxes3D
from sim.labels.geometry import GeomShapes
from sim.labels.ids import LabelIds
from sim.labels.occupancy import METHOD, OccupancyLabeler
from sim.labels.segmentation import Segmenter
from sim.registry import SensorProfile

log = logging.getLogger(__name__)


class LabelFrames:
    """``static()`` once per file, then ``capture(data, seg_images)`` -> (datasets, error text) per frame.

    `seg_images`: camera id -> that frame's segmentation, one of the forms `Segmenter.masks` takes:
    the `SegmentIds` of `sim.render.CameraRig(..., segments=True)` (read from the depth pass), an
    [H, W] geom-id image or mujoco.Renderer's [H, W, 2] (objid, objtype); needed only when
    `needs_segmentation`."""

    def __init__(self, scene, profile: SensorProfile):
        self.profile = profile
        self.modalities = tuple(m for m in schema.LABEL_MODALITIES if m in profile.modalities)
        model = scene.model
        self.ids = LabelIds.from_scene(scene)
        self.objects = self.ids.object_names
        shapes = GeomShapes(model)
        want = set(self.modalities)
        self.segmenter = Segmenter(self.ids) if self.needs_segmentation else None
        self.box2d = Box2DLabeler(model, self.ids, shapes) if "box2d" in want else None
        self.box3d = Box3DLabeler(model, self.ids, shapes) if "box3d" in want else None
        self.occupancy = (OccupancyLabeler(model, self.ids, profile.occupancy_bounds_m,
                                           profile.occupancy_voxel_size_m, shapes) if "occupancy" in want else None)
        # time spent so far per label (benchmarks): segmentation (masks), box2d, box3d, occupancy
        self.seconds: dict[str, float] = defaultdict(float)

    @property
    def needs_segmentation(self) -> bool:
        return "segmentation" in self.modalities or "box2d" in self.modalities

    def static(self) -> dict:
        if not self.modalities:
            return {}
        out = {"labels/semantic_classes": json.dumps(self.ids.semantic_json()),
               "labels/instances": json.dumps(self.ids.instances_json())}
        if self.box2d is not None:
            out["labels/box2d_semantics"] = json.dumps({"xyxy": schema.BOX2D_XYXY,
                                                        "visibility": schema.BOX2D_VISIBILITY}, sort_keys=True)
        if self.occupancy is not None:
            occ, root = self.occupancy, schema.OCCUPANCY_ROOT
            out[f"{root}/grid_shape"] = np.array(occ.shape, np.int64)
            out[f"{root}/bounds_m"] = occ.bounds
            out[f"{root}/voxel_size_m"] = np.float64(occ.voxel_size)
            out[f"{root}/method"] = METHOD
            out[f"{root}/semantics"] = json.dumps({
                "labels": self.ids.semantic_json(), "free": 0, "frame": "world",
                "voxel_centre": "bounds_m[0] + ([i, j, k] + 0.5) * voxel_size_m for grid[t, i, j, k]",
                "occupied": "the voxel centre is inside or on a labelled geom (primitives analytic, meshes by "
                            "containment); planes and the world body (floor) are left out",
                "overlap": "the higher semantic id wins, then the higher instance id",
                "instance_grid": "instance ids of labels/instances, 0 = no object",
            }, sort_keys=True)
        return out

    def capture(self, data: mujoco.MjData, seg_images: Mapping[str, np.ndarray] | None = None) -> tuple[dict, str]:
        frame, errors = {}, []
        if self.needs_segmentation:
            self._capture_images(data, seg_images or {}, frame, errors)
        if self.box3d is not None:
            t0 = time.perf_counter()
            try:
                boxes = self.box3d.capture(data)
            except Exception as exc:   # keep the episode: flag the frame instead of aborting
                log.warning("3D boxes failed: %s", exc)
                errors.append(f"box3d failed: {exc}")
                n = len(self.objects)
                boxes = Boxes3D(np.full((n, 3), np.nan), np.full((n, 3), np.nan), np.full((n, 4), np.nan))
            self.seconds["box3d"] += time.perf_counter() - t0
            for i, obj in enumerate(self.objects):
                frame[schema.box3d_path(obj, "center_world")] = boxes.center_world[i]
                frame[schema.box3d_path(obj, "size_lwh")] = boxes.size_lwh[i]
                frame[schema.box3d_path(obj, "quat_world")] = boxes.quat_world[i]
        if self.occupancy is not None:
            root = schema.OCCUPANCY_ROOT
            t0 = time.perf_counter()
            try:
                grid = self.occupancy.capture(data)
                semantic, instance, valid = grid.semantic, grid.instance, True
            except Exception as exc:
                log.warning("occupancy failed: %s", exc)
                errors.append(f"occupancy failed: {exc}")
                semantic = np.zeros(self.occupancy.shape, np.uint8)
                instance, valid = np.zeros(self.occupancy.shape, np.uint16), False
            self.seconds["occupancy"] += time.perf_counter() - t0
            frame[f"{root}/grid"], frame[f"{root}/instance_grid"] = semantic, instance
            frame[f"{root}/frame_valid"] = np.bool_(valid)
        return frame, "; ".join(errors)

    def _capture_images(self, data, seg_images: Mapping[str, np.ndarray], frame: dict, errors: list) -> None:
        h, w, n = self.profile.height, self.profile.width, len(self.objects)
        for cam in self.profile.camera_ids:
            t0 = time.perf_counter()
            try:
                if cam not in seg_images:
                    raise ValueError("no segmentation image")
                masks = self.segmenter.masks(seg_images[cam])
                if masks.instance.shape != (h, w):
                    raise ValueError(f"segmentation image of shape {masks.instance.shape}, expected {(h, w)}")
                semantic, instance = masks.semantic, masks.instance
            except Exception as exc:
                log.warning("labels of camera %s failed: %s", cam, exc)
                errors.append(f"labels of camera {cam} failed: {exc}")
                semantic, instance = np.zeros((h, w), np.uint8), np.zeros((h, w), np.uint16)
                masks = None
            t1 = time.perf_counter()
            self.seconds["segmentation"] += t1 - t0
            boxes = None
            if self.box2d is not None and masks is not None:
                try:        # a box failure keeps the (valid) masks
                    boxes = self.box2d.capture(data, cam, instance)
                except Exception as exc:
                    log.warning("2D boxes of camera %s failed: %s", cam, exc)
                    errors.append(f"2D boxes of camera {cam} failed: {exc}")
                self.seconds["box2d"] += time.perf_counter() - t1
            if "segmentation" in self.modalities:
                frame[f"cameras/{cam}/semantic_seg"] = semantic
                frame[f"cameras/{cam}/instance_seg"] = instance
            if self.box2d is not None:
                xyxy = boxes.xyxy if boxes is not None else np.full((n, 4), np.nan, np.float32)
                visibility = boxes.visibility if boxes is not None else np.zeros(n, np.float32)
                for i, obj in enumerate(self.objects):
                    frame[schema.box2d_path(cam, obj, "xyxy")] = xyxy[i]
                    frame[schema.box2d_path(cam, obj, "visibility")] = visibility[i]
