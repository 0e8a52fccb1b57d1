"""Zoned objects are drawn inside their zone, rectangular or round, the same way for the same seed."""

import copy

import numpy as np

from sim.registry import catalog_path, load_yaml
from sim.scene.sample import demonstration_sample
from sim.tasks import parse_task

PATH = catalog_path("tasks", "citrus_plate_loading")
CENTRE, RADIUS = np.array([0.2, -0.1]), 0.06


def _task_with_zones():
    raw = copy.deepcopy(load_yaml(PATH))
    raw["zones"] = {"round": {"center_xy": CENTRE.tolist(), "radius": RADIUS},
                    "strip": {"xy_min": [-0.4, -0.2], "xy_max": [-0.2, -0.1]}}
    del raw["objects"]["lemon_1"]["pose"]
    raw["objects"]["lemon_1"]["zone"] = "round"
    del raw["objects"]["lemon_2"]["pose"]
    raw["objects"]["lemon_2"]["zone"] = "strip"
    return parse_task(raw, PATH)


def test_round_and_rectangular_zones_are_sampled_inside_and_evenly():
    task = _task_with_zones()
    round_xy, strip_xy = [], []
    for seed in range(300):
        poses = demonstration_sample(task, seed).object_poses
        round_xy.append(poses["lemon_1"][:2])
        strip_xy.append(poses["lemon_2"][:2])
    dist = np.linalg.norm(np.array(round_xy) - CENTRE, axis=1)
    assert dist.max() <= RADIUS + 1e-6
    # uniform over the disc's area: a quarter of the draws fall within half the radius
    assert 0.17 < np.mean(dist < RADIUS / 2) < 0.33
    assert dist.max() > 0.9 * RADIUS
    strip = np.array(strip_xy)
    assert (strip >= [-0.4, -0.2]).all() and (strip <= [-0.2, -0.1]).all()
    assert np.ptp(strip[:, 0]) > 0.15 and np.ptp(strip[:, 1]) > 0.07


def test_zone_sampling_is_deterministic_per_seed():
    task = _task_with_zones()
    assert demonstration_sample(task, 7).to_json() == demonstration_sample(task, 7).to_json()
    assert demonstration_sample(task, 7).to_json() != demonstration_sample(task, 8).to_json()
