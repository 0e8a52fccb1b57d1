"""Pick field `place_either_end` (with `place_axis`): the object may stand on either end; where turning
`place_axis` down would run the hand into its own arm at the place (kinematic check), the other end goes down.
Standing the marker up in the pen cup (stationery_category_sorting), the UR5+Schunk's thumb base goes 4-5 cm into
its forearm with the marker's +x end down, and clears with -x down; the RM65+Revo2 clears either way, so its
timeline does not change. The check refuses it without place_axis."""

import pytest

from sim.errors import SpecError
from plan_runs import parse_steps, plan_steps_on, timeline_rows
from teleop.plan_steps.own_arm import OWN_ARM_DEPTH_M, into_own_arm

TASK = "stationery_category_sorting"
MARKER = {"hand": "right", "pick": "marker", "place": "pen_cup", "place_offset": [0.0, 0.0, -0.05],
          "grasp": "flat_pinch", "place_axis": [1.0, 0.0, 0.0]}


def _plan(steps):
    return parse_steps(TASK, steps)[1]


def _planned(embodiment: str, step: dict):
    return plan_steps_on(TASK, embodiment, [step], 0)


def _frames(op) -> list[tuple]:
    return timeline_rows(op.sides["right"])


def test_check_refuses_either_end_without_place_axis():
    step = {k: v for k, v in MARKER.items() if k != "place_axis"}
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.place_either_end"):
        _plan([{**step, "place_either_end": True}])


def test_the_schunk_stands_the_marker_on_its_other_end():
    plain, _ = _planned("ur5_schunk", MARKER)
    either, data = _planned("ur5_schunk", {**MARKER, "place_either_end": True})
    other, _ = _planned("ur5_schunk", {**MARKER, "place_axis": [-1.0, 0.0, 0.0]})
    assert _frames(either) == _frames(other) != _frames(plain)
    # the +x end down runs the thumb into the forearm over the cup; the -x end down keeps clear
    side = plain.sides["right"]
    poses = lambda op: [(f.pos, f.quat) for f in op.sides["right"]["timeline"].frames[9:13]]
    assert into_own_arm(plain, data, side, poses(plain), side["q_home"]) > 2 * OWN_ARM_DEPTH_M
    assert into_own_arm(either, data, side, poses(either), side["q_home"]) < OWN_ARM_DEPTH_M


def test_a_hand_clear_of_its_arm_keeps_the_axis():
    assert _frames(_planned("rm65_revo2", {**MARKER, "place_either_end": True})[0]) == \
        _frames(_planned("rm65_revo2", MARKER)[0])
