"""Two opt-in `pick` fields: `carry_s` (how long the carry from the lift to above the place takes) and, with
grasp: flat_pinch, `place_yaw` (of the turns that set the object square to its target, the one with the
tips closing along that direction: teleop/plan_steps/flat_place.py)."""

import numpy as np
import pytest

from sim.embodiment.frames import quat_to_mat
from sim.errors import SpecError
from teleop.flat_pinch import tip_axis
from teleop.operator_motion import DURATIONS
from teleop.plan_steps.flat_place import turn_toward
from teleop.plan_steps.pick_place import flat_pinch
from plan_runs import JIGSAW, JIGSAW_GREEN, looks_with_object_under_wrist, parse_steps, plan_steps_on

TASK, EMBODIMENT = JIGSAW
GREEN = JIGSAW_GREEN


def _op(step: dict):
    return plan_steps_on(TASK, EMBODIMENT, [step])


@pytest.mark.parametrize(("extra", "expected"), [
    ({"carry_s": 0}, r"seconds in \(0, 10\]"),
    ({"carry_s": 12}, r"seconds in \(0, 10\]"),
    ({"place_yaw": 200}, r"degrees in \[-180, 180\]"),
    ({"grasp": "power", "place_yaw": 0}, "no place_yaw without grasp: flat_pinch"),
    ({"place": "table", "place_offset": [0.2, 0.0], "place_yaw": 0}, "no place_yaw with place: table"),
])
def test_the_fields_are_checked(extra, expected):
    step = {**GREEN, **extra}
    if step["grasp"] != "flat_pinch":
        del step["grasp_yaw"]
    field = next(iter(extra.keys() - {"grasp", "place", "place_offset"}))
    with pytest.raises(SpecError, match=rf"field 'demo_plan\[0\]\.{field}'.*{expected}"):
        parse_steps(TASK, [step])


def test_carry_s_sets_how_long_the_carry_takes():
    """Carried for 3 s rather than the default second: the plan is 120 control steps longer, all of it
    in the carry (a long reach turning as it goes: the IIWA7's wrist lagged 0.9 rad at the default)."""
    default, slow = (_op(step)[0].sides["right"]["timeline"].frames for step in (GREEN, {**GREEN, "carry_s": 3}))
    assert slow[-1].end_step - default[-1].end_step == 3 * 60 - DURATIONS["carry"]
    # the lift ends at the same step in both; the hand is above the place 120 steps later
    lifted = max(i for i, f in enumerate(default) if f.end_step <= 300 and f.pos[2] > default[i - 1].pos[2] + 0.1)
    assert slow[lifted].end_step == default[lifted].end_step
    assert slow[lifted + 1].end_step - slow[lifted].end_step == 3 * 60


@pytest.mark.parametrize(("turn", "heading", "place_yaw", "expected"), [
    (-25, 115, 90, -25),        # already nearest: the smallest turn
    (-25, 115, 0, -115),        # a quarter turn further round sets the tips along x
    (-25, 115, 180, 65),
    (10, 0, -90, -80),
])
def test_turn_toward_picks_the_square_turn_nearest_the_place_yaw(turn, heading, place_yaw, expected):
    got = turn_toward(np.radians(turn), np.pi / 2, np.radians(heading), np.radians(place_yaw))
    assert np.degrees(got) == pytest.approx(expected)


def _heading_after_set_off(step: dict) -> float:
    """The tips' closing direction (degrees, thumb to fingers, world) as the hand comes down over the place,
    after the operator's look as the carry sets off (the piece seen 5 cm under the wrist, as it lies)."""
    op, data = _op(step)
    side = op.sides["right"]
    looks_with_object_under_wrist(op, data, "green_piece", ("set_off",))
    ready = flat_pinch(op, data, op.scene.task.demo_plan[0], "green_piece")[1]
    lower = side["timeline"].frames[-5]
    axis = quat_to_mat(lower.quat) @ tip_axis("sharpa", ready)
    return float(np.degrees(np.arctan2(axis[1], axis[0])))


@pytest.mark.parametrize("place_yaw", [0.0, 90.0, -90.0])
def test_place_yaw_turns_the_hand_so_the_tips_close_along_it(place_yaw):
    """Square to the white piece either way (the piece lies at ~19 degrees on seed 0), but with the tips'
    axis within 45 degrees of place_yaw: a piece set against another's side with the tips on its free
    sides (jigsaw's yellow piece: the tips landed on the white piece and held it 1.7 cm up)."""
    default = _heading_after_set_off(GREEN)
    heading = _heading_after_set_off({**GREEN, "place_yaw": place_yaw})
    off = (heading - place_yaw + 180) % 360 - 180
    assert abs(off) <= 45 + 1e-6
    assert (heading - default) % 90 == pytest.approx(0, abs=1e-6) or (heading - default) % 90 == pytest.approx(90, abs=1e-6)
