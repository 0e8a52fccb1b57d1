"""A flat pinch's opt-in release fields (teleop/plan_steps/flat_place.py): `release_pinch_only` opens only
the thumb and the pinching fingers, `place_press_m` sets the object down that far below its release height,
`release_relax` opens them from where they hold rather than to the pre-shape."""

import mujoco
import numpy as np
import pytest

from sim.errors import SpecError
from teleop.flat_pinch import tip_pinch
from teleop.plan_steps.flat_place import PRESS_M
from teleop.plan_steps.pick_place import flat_pinch
from plan_runs import JIGSAW, JIGSAW_GREEN, looks_with_object_under_wrist, parse_steps, plan_steps_on

TASK, EMBODIMENT = JIGSAW
GREEN = JIGSAW_GREEN


def _op(step: dict):
    return plan_steps_on(TASK, EMBODIMENT, [step])


@pytest.mark.parametrize(("extra", "expected"), [
    ({"grasp": "pinch", "release_pinch_only": True}, "no release_pinch_only without grasp: flat_pinch"),
    ({"grasp": "power", "place_press_m": 0.02}, "no place_press_m without grasp: flat_pinch"),
    ({"place_press_m": 0.05}, r"metres in \[0, 0.03\]"),
    ({"grasp": "power", "release_relax": 0.5}, "no release_relax without grasp: flat_pinch"),
    ({"release_relax": 0}, r"a fraction in \(0, 1\]"),
])
def test_the_release_fields_are_a_flat_pinchs_only(extra, expected):
    step = {**GREEN, **extra}
    if step["grasp"] != "flat_pinch":
        del step["grasp_yaw"]
    with pytest.raises(SpecError, match=rf"jigsaw_puzzle_assembly.yaml: field 'demo_plan\[0\]\.{next(iter(extra.keys() - {'grasp'}))}'.*{expected}"):
        parse_steps(TASK, [step])


def test_release_pinch_only_keeps_the_folded_fingers_as_they_held():
    op, data = _op({**GREEN, "release_pinch_only": True})
    frames = op.sides["right"]["timeline"].frames
    # from the end: back home, retreat, ease off, open, lower (holding)
    retreat, ease, opened, lower = frames[-2], frames[-3], frames[-4], frames[-5]
    ready = flat_pinch(op, data, op.scene.task.demo_plan[0], "green_piece")[1]     # the pre-shape it came down with
    pinching = tip_pinch("sharpa").moving
    assert pinching.any() and not pinching.all()
    assert np.allclose(opened.hand[pinching], ready[pinching])
    assert np.allclose(opened.hand[~pinching], lower.hand[~pinching])
    assert not np.allclose(ready[~pinching], lower.hand[~pinching])     # the default release moves them
    assert np.allclose(ease.hand, opened.hand) and np.allclose(retreat.hand, opened.hand)


def _lowered(step: dict) -> list:
    """The keyframes of a one-pick plan after the operator's two looks (setting off, starting down), the
    piece seen 5 cm under the wrist."""
    op, data = _op(step)
    looks_with_object_under_wrist(op, data, "green_piece", ("set_off", "lowering"))
    return op.sides["right"]["timeline"].frames


def test_place_press_m_sets_the_object_down_that_far_below_its_release_height():
    default, pressed = _lowered(GREEN), _lowered({**GREEN, "place_press_m": 0.02})
    for before, after in zip(default[-5:-1], pressed[-5:-1]):       # lower, open, ease off, retreat
        assert np.allclose(after.pos[:2], before.pos[:2])
        assert after.pos[2] - before.pos[2] == pytest.approx(-0.02 - PRESS_M, abs=1e-9)


def test_release_relax_opens_the_pinching_digits_from_where_they_hold():
    """As the hand is about to open, the operator reads the hand's joints: the thumb and the pinching fingers
    go that fraction of the way from there to the open hand, for the open, ease-off and retreat keyframes."""
    op, data = _op({**GREEN, "release_relax": 0.6})
    side = op.sides["right"]
    frames = side["timeline"].frames
    lower = frames[-5]
    relax = [adjust for _, adjust in side["looks"] if adjust.__name__ == "relax"]
    assert len(relax) == 1
    data.qpos[:] += 0.1      # a hand that holds somewhere else than the plan's targets
    mujoco.mj_forward(op.scene.model, data)
    held = data.actuator_length[side["hand_ids"]].copy()
    relax[0](data)
    pinching = tip_pinch("sharpa").moving
    for frame in frames[-4:-1]:     # open, ease off, retreat
        assert np.allclose(frame.hand[pinching], (held + 0.6 * (side["open"] - held))[pinching])
        assert np.allclose(frame.hand[~pinching], lower.hand[~pinching])
