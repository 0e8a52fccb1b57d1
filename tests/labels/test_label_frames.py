"""Labels on a real task scene (citrus_plate_loading on ur5_rh5dg2), as the render stage stores them."""

import json

import h5py
import mujoco
import numpy as np
import pytest

from episodes import schema
from episodes.label_frames import LabelFrames
from episodes.validate import validate_episode
from episodes.writer import EpisodeWriter
from sim.labels.segmentation import render_segmentation
from sim.registry import parse_sensor_profile, sensor_profile
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample
from sim.tasks import load_task

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"
ALL_LABELS = ["rgb", "depth", "segmentation", "box2d", "box3d", "occupancy"]


def _profile(modalities=ALL_LABELS):
    raw = sensor_profile("preview").raw
    raw = {**raw, "cameras": {**raw["cameras"], "modalities": list(modalities), "width": 96, "height": 72},
           "occupancy": {"bounds_m": [[-0.6, -0.4, 0.65], [0.6, 0.4, 1.25]], "voxel_size_m": 0.01}}
    return parse_sensor_profile(raw, "test_profile.yaml")


@pytest.fixture(scope="module")
def posed():
    spec = load_task(TASK)
    scene = build_scene(spec, EMBODIMENT, demonstration_sample(spec, 0))
    return scene, scene.home_data()


def _segmentation(scene, data, profile):
    with mujoco.Renderer(scene.model, height=profile.height, width=profile.width) as renderer:
        out = {}
        for cam in profile.camera_ids:
            renderer.update_scene(data, camera=cam)
            out[cam] = render_segmentation(renderer)
        return out


def test_every_task_object_gets_boxes_occupancy_and_pixels(posed):
    scene, data = posed
    profile = _profile()
    labels = LabelFrames(scene, profile)
    frame, error = labels.capture(data, _segmentation(scene, data, profile))
    assert error == ""
    assert labels.objects == tuple(scene.object_names + scene.distractor_names)
    instances = frame[f"{schema.OCCUPANCY_ROOT}/instance_grid"]
    for inst, name in enumerate(labels.objects, start=1):
        size = frame[schema.box3d_path(name, "size_lwh")]
        assert np.all(np.isfinite(size)) and np.all(size > 0.01), name
        centre = frame[schema.box3d_path(name, "center_world")]
        np.testing.assert_allclose(centre[:2], data.xpos[scene.model.body(name).id][:2], atol=1e-9)
        assert (instances == inst).sum() > 10, name
        # the overhead camera sees the whole table
        assert frame[schema.box2d_path("overhead", name, "visibility")] > 0.9, name
        assert np.all(np.isfinite(frame[schema.box2d_path("overhead", name, "xyxy")])), name
    semantic = frame["cameras/overhead/semantic_seg"]
    names = labels.ids.semantic_names
    seen = {names[i] for i in np.unique(semantic)}
    assert {"table", "plate", "lemon", "orange"} <= seen
    assert any(n.startswith("robot_") and n.endswith("_hand") for n in seen)
    grid = frame[f"{schema.OCCUPANCY_ROOT}/grid"]
    assert grid.shape == (120, 80, 60) and (grid == names.index("table")).sum() > 0
    assert frame[f"{schema.OCCUPANCY_ROOT}/frame_valid"]


def test_a_missing_segmentation_image_is_flagged_not_raised(posed):
    scene, data = posed
    profile = _profile()
    segs = _segmentation(scene, data, profile)
    del segs["chest"]
    frame, error = LabelFrames(scene, profile).capture(data, segs)
    assert "labels of camera chest failed: no segmentation image" in error
    assert not frame["cameras/chest/instance_seg"].any()
    assert np.isnan(frame[schema.box2d_path("chest", "plate", "xyxy")]).all()
    assert frame[schema.box2d_path("overhead", "plate", "visibility")] > 0.9      # other cameras unaffected
    assert frame[f"{schema.OCCUPANCY_ROOT}/frame_valid"]


def test_only_the_listed_modalities_are_produced(posed):
    scene, data = posed
    labels = LabelFrames(scene, _profile(["rgb", "depth", "box3d"]))
    assert not labels.needs_segmentation
    frame, error = labels.capture(data, None)
    assert error == "" and frame and all(key.startswith("labels/box3d/") for key in frame)
    assert len(frame) == 3 * len(labels.objects)     # center_world, size_lwh, quat_world per object
    assert LabelFrames(scene, _profile(["rgb"])).static() == {}


def _write(path, scene, data, profile, frames=2):
    labels = LabelFrames(scene, profile)
    static = {**labels.static(), "meta/modalities": json.dumps(list(labels.modalities)),
              "meta/collection_config": json.dumps({"profile": profile.raw})}
    segs = _segmentation(scene, data, profile) if labels.needs_segmentation else None
    with EpisodeWriter(path, static) as writer:
        for _ in range(frames):
            frame, _ = labels.capture(data, segs)
            writer.append(frame)


def _label_problems(path):
    """The validator's findings about labels (the file holds nothing else of an episode)."""
    keys = ("labels/", "semantic_seg", "instance_seg", "meta/modalities")
    return [p for p in validate_episode(path) if any(k in p for k in keys)]


def test_stored_labels_validate_and_damage_is_reported(posed, tmp_path):
    scene, data = posed
    profile = _profile()
    path = tmp_path / "labels.hdf5"
    _write(path, scene, data, profile)
    assert _label_problems(path) == []
    with h5py.File(path, "a") as f:
        assert f["cameras/overhead/instance_seg"].shape == (2, 72, 96)
        assert f[f"{schema.OCCUPANCY_ROOT}/grid"].shape == (2, 120, 80, 60)
        del f["labels/box3d/plate/size_lwh"]
        del f["labels/box2d/chest/lemon_1"]
        data_ = f["cameras/left_wrist/semantic_seg"][()]
        del f["cameras/left_wrist/semantic_seg"]
        f["cameras/left_wrist/semantic_seg"] = data_.astype(np.int32)
        f["labels/box3d/ghost/center_world"] = np.zeros((2, 3))
        f[f"{schema.OCCUPANCY_ROOT}/grid_shape"][...] = [1, 2, 3]
    problems = _label_problems(path)
    assert "labels/box3d/plate/size_lwh: missing (dataset)" in problems
    assert "labels/box2d/chest/lemon_1/xyxy: missing (dataset)" in problems
    assert "labels/box2d/chest/: missing ['lemon_1'] (listed in labels/instances)" in problems
    assert "cameras/left_wrist/semantic_seg: dtype int32, expected uint8" in problems
    assert "labels/box3d/: ['ghost'] are not listed in labels/instances" in problems
    assert any(p.startswith(f"{schema.OCCUPANCY_ROOT}/grid_shape: [1, 2, 3]") for p in problems)


def test_labels_the_profile_lists_are_required(posed, tmp_path):
    scene, data = posed
    path = tmp_path / "no_labels.hdf5"
    _write(path, scene, data, _profile(["rgb", "box3d"]))
    with h5py.File(path, "a") as f:     # the collection profile asked for occupancy too
        f["meta/collection_config"][()] = json.dumps({"profile": _profile().raw})
    problems = _label_problems(path)
    assert f"{schema.OCCUPANCY_ROOT}/grid: missing (dataset)" in problems
    assert f"{schema.OCCUPANCY_ROOT}/frame_valid: missing (dataset)" in problems
    assert not [p for p in problems if "box3d" in p]
    with h5py.File(path, "a") as f:     # labels present but not listed
        f["meta/modalities"][()] = json.dumps([])
    assert "meta/modalities: expected 'box3d' in the list, since its labels are present" in _label_problems(path)


def test_label_frames_are_deterministic(posed):
    scene, data = posed
    profile = _profile()
    segs = _segmentation(scene, data, profile)
    a, _ = LabelFrames(scene, profile).capture(data, segs)
    b, _ = LabelFrames(scene, profile).capture(data, _segmentation(scene, data, profile))
    assert a.keys() == b.keys()
    for key in a:
        assert np.asarray(a[key]).tobytes() == np.asarray(b[key]).tobytes(), key
