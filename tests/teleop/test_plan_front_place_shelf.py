"""`place_from: front` into a compartment of a container with a shelf across its cavity's middle (the
fridge of fridge_fruit_shelf_sorting): the rays that find the opening start at the height the object is
let go at, not at the cavity's centre, which lies inside the shelf (from there every ray meets the
shelf and no side looked open)."""

import numpy as np
import pytest
import yaml

from sim.errors import SpecError
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample
from sim.tasks import load_task, parse_task
from teleop.plan_steps.front_place import RELEASE_GAP_M, opening
from plan_runs import home_and_plan

TASK, EMBODIMENT = "fridge_fruit_shelf_sorting", "ur5_shadow"
SHELF_TOP = 0.238       # the shelf's top above the cavity floor (fridge frame: floor -0.235, shelf 0 +- 0.003)
STEP = {"hand": "right", "pick": "lemon", "place": "fridge", "place_from": "front",
        "place_offset": [0.08, 0.0, SHELF_TOP]}


def _planned(tmp_path):
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    raw["objects"]["fridge"]["parts"][1]["pos"] = [0.0, 0.008, 0.0]     # the shelf across the cavity's middle
    raw["demo_plan"] = [STEP]
    task = parse_task(raw, tmp_path / "fridge.yaml")
    scene = build_scene(task, EMBODIMENT, demonstration_sample(task, 0))
    data, op = home_and_plan(scene)
    return scene, data, op


def test_from_the_cavity_centre_every_ray_starts_in_the_shelf(tmp_path):
    """Why the rays start elsewhere: from the cavity's centre (in the shelf) no side is open."""
    scene, data, _ = _planned(tmp_path)
    fridge = scene.object_body_ids["fridge"]
    R = data.xmat[fridge].reshape(3, 3)
    centre = data.xpos[fridge] + R @ np.asarray(scene.task.objects["fridge"].interior_offset)
    with pytest.raises(SpecError, match="a container open at a side"):
        opening(scene.model, data, fridge, centre, np.array([0.0, -1.0, 1.0]))


def test_the_lemon_goes_in_through_the_front_onto_the_shelf(tmp_path):
    """Planned (no error), the way in is the fridge's own -y, and the lemon is let go over the shelf in
    the upper compartment, just above the shelf's top."""
    scene, data, op = _planned(tmp_path)
    fridge = scene.object_body_ids["fridge"]
    R = data.xmat[fridge].reshape(3, 3)
    shelf_z = float((data.xpos[fridge] + R @ np.array([0.0, 0.0, 0.003]))[2])
    lemon = scene.task.objects["lemon"]
    (left_at,) = [p for _, n, p, on in op.moves if n == "lemon" and on == "fridge"]
    assert left_at[2] + RELEASE_GAP_M == pytest.approx(shelf_z + lemon.rest_height + RELEASE_GAP_M, abs=2e-3)
    assert left_at[:2] - data.xpos[fridge][:2] == pytest.approx([0.08, 0.0], abs=1e-6)   # place_offset: world dx, dy
    frames = op.sides["right"]["timeline"].frames
    released = next(k for k in range(1, len(frames)) if np.array_equal(frames[k].hand, op.sides["right"]["open"])
                    and not np.array_equal(frames[k - 1].hand, op.sides["right"]["open"]))
    outside, inside = frames[released - 3].pos, frames[released - 2].pos
    way_in = (inside - outside) / np.linalg.norm(inside - outside)
    assert np.allclose(way_in, R[:, 1], atol=1e-6), "slid straight in along the fridge's +y"
