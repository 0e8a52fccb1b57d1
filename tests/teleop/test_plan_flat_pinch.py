"""`grasp: flat_pinch`: the plan check refuses what it cannot use, the tip pinch found from the
hand's kinematics, and a real lift of a 1.6 cm jigsaw piece off the table."""

import numpy as np
import pytest

from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task, parse_task
from teleop.flat_pinch import flat_pinch_rotation, tip_pinch, tip_points, tip_preshape
from teleop.pinch_grasp import MEET_M, hand_kinematics
from teleop.transit import hand_outline

from plan_runs import JIGSAW, JIGSAW_GREEN_TO_TABLE, home_and_plan, rise_through_lift
from task_files import task_file_with_plan

TASK, EMBODIMENT = JIGSAW
PICK = JIGSAW_GREEN_TO_TABLE


def _raw(step: dict) -> dict:
    return task_file_with_plan(TASK, [step])


def test_flat_pinch_is_a_plan_grasp(tmp_path):
    assert parse_task(_raw(dict(PICK)), tmp_path / "jigsaw.yaml").demo_plan[0]["grasp"] == "flat_pinch"


@pytest.mark.parametrize(("field", "value", "expected"), [
    ("approach_pitch_deg", 30, "no approach_pitch_deg with grasp: flat_pinch"),
    ("grasp", "flat", "one of .*'flat_pinch'"),
])
def test_flat_pinch_refuses_what_it_cannot_use(tmp_path, field, value, expected):
    with pytest.raises(SpecError, match=rf"jigsaw.yaml: field 'demo_plan\[0\].{field}'.*{expected}"):
        parse_task(_raw({**PICK, field: value}), tmp_path / "jigsaw.yaml")


@pytest.mark.parametrize("hand", ["sharpa", "orca"])
def test_tip_pinch_brings_the_tips_together_at_the_bottom_of_the_hand(hand):
    """The thumb's tip meets the fingers' tips; turned for the flat pinch, the spread hand's tips are
    its lowest points (within a few millimetres: the tips are on the pads' side of the fingers' ends)."""
    grasp = tip_pinch(hand)
    assert grasp.gap_m <= MEET_M
    kin = hand_kinematics(hand)
    touch, _ = tip_preshape(hand, kin.home, grasp.close, 0.03)
    R = flat_pinch_rotation(hand, "right", touch)
    tips_z = (tip_points(hand, grasp.fingers, touch) @ R.T)[:, 2]
    lowest = (hand_outline(hand, "right", touch) @ R.T)[:, 2].min()
    assert tips_z.max() - lowest < 0.006


def test_flat_pinch_lifts_a_jigsaw_piece():
    """A 10 x 10 x 1.6 cm piece lying flat, lifted clear of the table (direct joint path, seed 0)."""
    spec = load_task(TASK)
    spec = type(spec)(**{**spec.__dict__, "demo_plan": [dict(PICK)]})
    scene = demonstration_scene(spec, EMBODIMENT)
    data, op = home_and_plan(scene)
    assert rise_through_lift(scene, data, op, "green_piece") > 0.08


def test_a_flat_pinch_closes_either_side_of_its_grasp_point():
    """grasp_point moves where the tips close (a spatula's handle clear of its blade): the hand's
    plan shifts by the point, turned with the object, and the hand keeps its turn."""
    from teleop.plan_steps.pick_place import flat_pinch
    spec = load_task(TASK)
    scene = demonstration_scene(spec, EMBODIMENT)
    data, op = home_and_plan(scene)
    point = [0.02, -0.01, 0.0]
    rot, _, centred, _ = flat_pinch(op, data, dict(PICK), "green_piece")
    rot_at, _, at, _ = flat_pinch(op, data, {**PICK, "grasp_point": point}, "green_piece")
    body_rot = data.xmat[scene.object_body_ids["green_piece"]].reshape(3, 3)
    assert np.allclose(rot_at, rot)
    assert np.allclose(at[:2], centred[:2] - (body_rot @ point)[:2], atol=1e-9)
    assert parse_task(_raw({**PICK, "grasp_point": point}), spec.source).demo_plan[0]["grasp_point"] == point


def test_flat_pinch_is_for_steps_that_pick_a_thing_lying_flat(tmp_path):
    """`pick` and `strike` (a hammer lying flat) take a flat pinch; a handover, which passes an object
    held in the air, is refused it, the grasps it takes named."""
    strike = {"hand": "right", "strike": "white_piece", "tool": "green_piece", "strike_point": [0.0, 0.0, 0.0],
              "place": "table", "place_offset": [0.1, 0.1], "grasp": "flat_pinch"}
    assert parse_task(_raw(strike), tmp_path / "jigsaw.yaml").demo_plan[0]["grasp"] == "flat_pinch"
    raw = _raw({"hand": "right", "handover": "green_piece", "to_hand": "left", "at": [0.0, 0.0, 0.2],
                "grasp": "flat_pinch"})
    with pytest.raises(SpecError, match=r"jigsaw.yaml: field 'demo_plan\[0\].grasp'.*\['side', 'power'\]"):
        parse_task(raw, tmp_path / "jigsaw.yaml")
