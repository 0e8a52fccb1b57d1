"""Cost of the labels per frame against the RGB render of the same cameras, measured in one run.

For `frames` posed states of a task scene (the robot holding home while the objects settle), every
camera of the profile is placed once in the render stage's renderer (`sim.offscreen`) and rendered
as RGB (the baseline), as depth alone, and as depth with the geom ids read from the same pass (what
the render stage does when labels need segmentation); then the masks, the 2D boxes, the 3D boxes
and the occupancy grid are computed. Figures are milliseconds per frame (all cameras) and per camera.
The segmentation render costs `depth_and_geom_ids - depth` next to a depth modality, and the whole
`depth_and_geom_ids` pass for a profile without depth.

    python -m sim.labels.bench --profile paper
"""

from __future__ import annotations

import argparse
import json
import time

from sim import physics
from sim.labels.box2d import Box2DLabeler
from sim.labels.box3d import Box3DLabeler
from sim.labels.geometry import GeomShapes
from sim.labels.ids import LabelIds
from sim.labels.occupancy import OccupancyLabeler
from sim.labels.segmentation import Segmenter
from sim.offscreen import OffscreenRenderer
from sim.registry import SensorProfile, names, sensor_profile
from sim.render import apply_antialias, apply_tessellation
from sim.scene.builder import demonstration_scene

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"
STEPS_BETWEEN_FRAMES = 3     # control steps between frames: the 20 Hz spacing
CAMERA_KEYS = ("scene_update", "rgb", "depth", "depth_and_geom_ids", "segmentation_masks", "box2d")


def run_bench(profile: str | SensorProfile = "paper", frames: int = 10, task: str = TASK,
              embodiment: str = EMBODIMENT) -> dict:
    profile = sensor_profile(profile) if isinstance(profile, str) else profile
    scene = demonstration_scene(task, embodiment)
    model, data = scene.model, scene.home_data()
    t0 = time.perf_counter()
    ids = LabelIds.from_scene(scene)
    shapes = GeomShapes(model)
    segmenter = Segmenter(ids)
    box2d, box3d = Box2DLabeler(model, ids, shapes), Box3DLabeler(model, ids, shapes)
    occupancy = OccupancyLabeler(model, ids, profile.occupancy_bounds_m, profile.occupancy_voxel_size_m, shapes)
    setup_s = time.perf_counter() - t0
    seconds = dict.fromkeys(CAMERA_KEYS + ("box3d", "occupancy"), 0.0)
    clock = time.perf_counter
    apply_antialias(model, profile)     # as the render stage's camera rig
    apply_tessellation(model, profile)
    renderer = OffscreenRenderer(model, profile.width, profile.height, shadows=profile.shadows)
    try:
        for _ in range(frames):
            for _ in range(STEPS_BETWEEN_FRAMES):
                physics.step_control(model, data, scene.layout.home_ctrl)
            for cam in profile.camera_ids:
                marks = [clock()]
                renderer.update(data, model.camera(cam).id)
                marks.append(clock())
                renderer.color()
                marks.append(clock())
                renderer.depth_and_geoms(False)
                marks.append(clock())
                _, segments = renderer.decode(*renderer.id_pass(True))     # as the render stage reads them
                marks.append(clock())
                masks = segmenter.masks(segments)
                marks.append(clock())
                box2d.capture(data, cam, masks.instance)
                marks.append(clock())
                for key, a, b in zip(CAMERA_KEYS, marks, marks[1:]):
                    seconds[key] += b - a
            t0 = clock()
            box3d.capture(data)
            t1 = clock()
            occupancy.capture(data)
            seconds["box3d"] += t1 - t0
            seconds["occupancy"] += clock() - t1
    finally:
        renderer.close()
    ms = {k: round(1e3 * v / frames, 3) for k, v in seconds.items()}
    segmentation_render = ms["depth_and_geom_ids"] - ms["depth"]
    labels = segmentation_render + ms["segmentation_masks"] + ms["box2d"] + ms["box3d"] + ms["occupancy"]
    cams = len(profile.camera_ids)
    return {
        "profile": profile.name, "task": task, "embodiment": embodiment, "frames": frames, "cameras": cams,
        "resolution": [profile.width, profile.height], "occupancy_grid": list(occupancy.shape),
        "occupancy_voxel_m": occupancy.voxel_size, "objects": len(ids.object_names), "geoms": model.ngeom,
        "ms_per_frame": {**ms, "segmentation_render_next_to_depth": round(segmentation_render, 3)},
        "ms_per_camera": {k: round(ms[k] / cams, 3) for k in CAMERA_KEYS},
        "labels_ms_per_frame": round(labels, 3),
        "labels_vs_rgb_ratio": round(labels / ms["rgb"], 3) if ms["rgb"] else None,
        "setup_s": round(setup_s, 3),
        "note": "baseline = RGB render of the same cameras in the same run (shadows as the profile says); "
                "labels = segmentation render next to depth (depth_and_geom_ids - depth) + masks + box2d + "
                "box3d + occupancy",
    }


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="paper")
    parser.add_argument("--frames", type=int, default=10)
    args = parser.parse_args()
    print(json.dumps(run_bench(args.profile, args.frames), indent=2))
