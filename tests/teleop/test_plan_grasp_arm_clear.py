"""Pick field `grasp_arm_clear` (a flat pinch): where the arm at the closed grasp runs into the scene (kinematic
check), the hand takes another of its near-best turns for the tips (teleop/flat_pinch.py near_rotations) whose arm
keeps clear. Taking the marker with the RH5DG2's round pinch (stationery_category_sorting, seed 1), the UR5's
wrist_1 link presses on the pen cup's rim; turned another way it clears. The RM65+Revo2's arm clears as planned,
so its timeline does not change. The check refuses it off a flat pinch."""

import numpy as np
import pytest

from sim.errors import SpecError
from plan_runs import parse_steps, plan_steps_on, timeline_rows
from teleop.flat_pinch import flat_pinch_rotation, near_rotations, tip_pinch, tip_preshape
from teleop.operator_motion import quat
from teleop.plan_steps.own_arm import OWN_ARM_DEPTH_M, arm_into_scene
from teleop.plan_steps.pick import round_pinched
from teleop.plan_steps.pick_place import flat_pinch, flat_pinch_turned

TASK = "stationery_category_sorting"
MARKER = {"hand": "right", "pick": "marker", "place": "pen_cup", "place_offset": [0.0, 0.0, -0.05],
          "grasp": "flat_pinch", "place_axis": [1.0, 0.0, 0.0], "round_pinch": True}


def _plan(steps):
    return parse_steps(TASK, steps)[1]


def _planned(embodiment: str, step: dict, seed: int):
    return plan_steps_on(TASK, embodiment, [step], seed)


def _frames(op) -> list[tuple]:
    return timeline_rows(op.sides["right"])


def _depth(op, data, pinch) -> float:
    """How deep the right arm goes into the scene at the pinch's closed grasp."""
    hand_rot, _, offset, closing = pinch
    grasp = op.object_pos(data, "marker") - offset
    side = op.sides["right"]
    return arm_into_scene(op, data, side, [(np.array([*grasp[:2], closing[-1][2]]), quat(hand_rot))], side["q"])


@pytest.mark.parametrize("grasp", ["pinch", "power"])
def test_check_refuses_grasp_arm_clear_off_a_flat_pinch(grasp):
    step = {k: v for k, v in MARKER.items() if k not in ("place_axis", "round_pinch")}
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.grasp_arm_clear"):
        _plan([{**step, "grasp": grasp, "grasp_arm_clear": True}])


def test_the_near_rotations_start_with_the_flat_pinch_rotation():
    """Spread for the 1.8 cm marker, the RH5DG2's [index, middle] pinch has other turns nearly as good (3 mm)."""
    fingers = ("index", "middle")
    pinch = tip_pinch("rh5dg2", fingers)
    ready, _ = tip_preshape("rh5dg2", np.zeros_like(pinch.close), pinch.close, 0.018 + 0.025, fingers)
    turns = near_rotations("rh5dg2", "right", tuple(np.round(ready, 6)), fingers)
    assert len(turns) > 1
    np.testing.assert_array_equal(turns[0], flat_pinch_rotation("rh5dg2", "right", ready, fingers))


def test_the_ur5_rh5dg2_turns_its_hand_where_its_arm_meets_the_cup():
    op, data = _planned("ur5_rh5dg2", MARKER, 1)
    step = round_pinched(op, MARKER)
    assert _depth(op, data, flat_pinch_turned(op, data, step, "marker")) > OWN_ARM_DEPTH_M      # wrist_1 on the rim
    assert _depth(op, data, flat_pinch(op, data, {**step, "grasp_arm_clear": True}, "marker")) <= OWN_ARM_DEPTH_M
    cleared, _ = _planned("ur5_rh5dg2", {**MARKER, "grasp_arm_clear": True}, 1)
    assert _frames(cleared) != _frames(op)


@pytest.mark.parametrize("seed", [0, 4])
def test_an_arm_clear_as_planned_keeps_its_timeline(seed):
    """The RM65+Revo2's arm keeps out of the scene at its marker grasp: the plan as without the field."""
    with_field, _ = _planned("rm65_revo2", {**MARKER, "grasp_arm_clear": True}, seed)
    without, _ = _planned("rm65_revo2", MARKER, seed)
    assert _frames(with_field) == _frames(without)
