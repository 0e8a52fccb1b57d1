"""`grasp_tips_height_m` on a flat pinch: the hand comes down so that its closed tips end that high over the
object's bottom (half a handle's height), pressed into the table no deeper than by default. By default the
hand's lowest point goes 8 mm into the table; on the linkage hands (one actuator per finger, the tip the
lowest point) that put the closed tips 2-3 mm inside it, the index stuck on the table under the pressing
wrist and never closed on baking_tray_prep's 12 mm spatula handle (ur5_rh5dg2, ur5_rh56dfx: 0 of 3)."""

import pytest

from sim.embodiment.mirror import M
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task, parse_task
from teleop.flat_pinch import tip_pinch, tip_points
from teleop.plan_steps.pick_place import FLAT_PINCH_PRESS_M, flat_pinch
from teleop.transit import bounding_box_points

from plan_runs import home_and_plan, rise_through_lift
from task_files import task_file_with_plan

TASK = "baking_tray_prep"
PICK = {"hand": "left", "pick": "spatula", "place": "tray", "place_offset": [-0.07, -0.08, -0.018],
        "grasp": "flat_pinch", "grasp_point": [-0.03, 0, 0]}
HEIGHT = {**PICK, "grasp_tips_height_m": 0.007}


@pytest.mark.parametrize(("fields", "expected"), [
    ({"grasp": "pinch", "grasp_point": None}, "no grasp_tips_height_m without grasp: flat_pinch"),
    ({"grasp_tips_height_m": 0.05}, "metres in \\[0, 0.03\\]"),
])
def test_the_tips_height_is_a_flat_pinch_field(tmp_path, fields, expected):
    step = {k: v for k, v in {**HEIGHT, **fields}.items() if v is not None}
    with pytest.raises(SpecError, match=rf"tray.yaml: field 'demo_plan\[0\].grasp_tips_height_m'.*{expected}"):
        parse_task(task_file_with_plan(TASK, [step]), tmp_path / "tray.yaml")


def _closed_tips_over_bottom(embodiment: str, step: dict) -> float:
    """How high the planned closed tips (the last closing stage's wrist) are over the object's bottom."""
    scene = demonstration_scene(load_task(TASK), embodiment)
    data, op = home_and_plan(scene)
    hand = op.sides["left"]["hand"]
    hand_rot, _, _, closing = flat_pinch(op, data, step, "spatula")
    q, wrist_z = closing[-1][1], closing[-1][2]
    tips = (tip_points(hand, tip_pinch(hand).fingers, q) @ M) @ hand_rot.T
    bottom = bounding_box_points(scene.model, data, scene.object_body_ids["spatula"])[:, 2].min()
    return float(wrist_z + tips[:, 2].min() - bottom)


def test_the_closed_tips_end_at_the_height_asked_not_inside_the_table():
    assert _closed_tips_over_bottom("ur5_rh5dg2", PICK) < -0.001          # by default: inside the table
    assert _closed_tips_over_bottom("ur5_rh5dg2", HEIGHT) == pytest.approx(0.007, abs=1e-6)


def test_no_deeper_than_by_default():
    """A hand whose closed tips sit high over its lowest point (the Allegro's, 3 cm) keeps the default press."""
    default, asked = _closed_tips_over_bottom("panda_allegro", PICK), _closed_tips_over_bottom("panda_allegro", HEIGHT)
    assert asked == pytest.approx(default, abs=1e-9) and default > 0.007 + FLAT_PINCH_PRESS_M / 2


def test_the_linkage_hand_lifts_the_spatula():
    """Direct joint path, seed 0: with the tips closing 7 mm up the handle the RH5DG2 lifts the spatula."""
    spec = load_task(TASK)
    heights = {}
    for name, step in (("default", PICK), ("asked", HEIGHT)):
        scene = demonstration_scene(type(spec)(**{**spec.__dict__, "demo_plan": [dict(step)]}), "ur5_rh5dg2")
        data, op = home_and_plan(scene)
        heights[name] = rise_through_lift(scene, data, op, "spatula", hand="left")
    assert heights["asked"] > 0.08 and heights["default"] < 0.02


def test_a_squeezed_pinch_ends_its_tips_at_the_height_asked():
    """With grasp_squeeze_m the last stage curls the tips past each other, 3-5 mm higher than the unsqueezed
    shape: the height asked is where the squeezed tips end (tool_box_loading's wrench head, 10 mm thick)."""
    spec = load_task("tool_box_loading")
    step = {"hand": "left", "pick": "wrench", "place": "box", "place_offset": [-0.1, -0.04], "grasp": "flat_pinch",
            "grasp_point": [0.078, 0, 0], "grasp_squeeze_m": 0.02, "grasp_tips_height_m": 0.005}
    scene = demonstration_scene(spec, "ur5_wuji")
    data, op = home_and_plan(scene)
    hand = op.sides["left"]["hand"]
    hand_rot, _, _, closing = flat_pinch(op, data, step, "wrench")
    tips = (tip_points(hand, tip_pinch(hand).fingers, closing[-1][1]) @ M) @ hand_rot.T
    bottom = bounding_box_points(scene.model, data, scene.object_body_ids["wrench"])[:, 2].min()
    assert closing[-1][2] + tips[:, 2].min() - bottom == pytest.approx(0.005, abs=1e-6)
