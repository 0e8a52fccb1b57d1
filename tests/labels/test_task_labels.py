"""Every object of every task, on the task's paper embodiment, gets a 3D box and occupied voxels in the
paper profile's grid (generated shapes, articulated links and fixed bases included)."""

import mujoco
import numpy as np
import pytest

from sim.labels.box3d import Box3DLabeler
from sim.labels.ids import LabelIds
from sim.labels.occupancy import OccupancyLabeler
from sim.registry import names, sensor_profile
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample
from sim.tasks import load_task


@pytest.mark.parametrize("task", names("tasks"))
def test_every_object_gets_a_box_and_voxels(task):
    spec = load_task(task)
    scene = build_scene(spec, spec.paper_embodiment, demonstration_sample(spec, 0))
    data = scene.home_data()
    ids = LabelIds.from_scene(scene)
    assert ids.object_names == tuple(scene.object_names + scene.distractor_names)
    paper = sensor_profile("paper")
    grid = OccupancyLabeler(scene.model, ids, paper.occupancy_bounds_m, paper.occupancy_voxel_size_m).capture(data)
    boxes = Box3DLabeler(scene.model, ids).capture(data)
    voxels = np.bincount(grid.instance.ravel(), minlength=len(ids.instance_names))
    for inst, name in enumerate(ids.object_names, start=1):
        assert voxels[inst] > 0, f"{name}: no occupied voxel"
        assert np.all(np.isfinite(boxes.size_lwh[inst - 1])) and np.all(boxes.size_lwh[inst - 1] > 0), name
        # the object's voxels lie inside its (slightly padded) 3D box
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, boxes.quat_world[inst - 1])
        cells = np.argwhere(grid.instance == inst)
        centres = paper.occupancy_bounds_m[0] + (cells + 0.5) * paper.occupancy_voxel_size_m
        local = (centres - boxes.center_world[inst - 1]) @ R.reshape(3, 3)
        assert np.all(np.abs(local) <= boxes.size_lwh[inst - 1] / 2 + 1e-9), name
