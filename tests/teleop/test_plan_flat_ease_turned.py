"""A flat pinch's opt-in `ease_turned` (teleop/plan_steps/flat_place.py): after opening, the hand slides off the
thumb's side of the hand as the operator's look turned it square, not along the direction planned before the turn
(jigsaw's yellow piece, its hand turned a quarter by place_yaw: slid along the piece's side and dragged it 2-3 cm)."""

import numpy as np
import pytest

from sim.embodiment.frames import quat_to_mat
from sim.errors import SpecError
from teleop.flat_pinch import tip_axis
from teleop.plan_steps.flat_place import EASE_M
from teleop.plan_steps.pick_place import flat_pinch
from plan_runs import looks_with_object_under_wrist, parse_steps, plan_steps_on

TASK, EMBODIMENT = "jigsaw_puzzle_assembly", "iiwa7_sharpa"
GREEN = {"hand": "right", "pick": "green_piece", "place": "white_piece", "place_offset": [0.108, -0.02, -0.016],
         "grasp": "flat_pinch", "grasp_yaw": 90}


def _ease_and_away(step: dict) -> tuple[np.ndarray, np.ndarray]:
    """After the look as the hand sets off: the ease off's horizontal move from the opened hand, and the
    horizontal unit vector from the turned hand's fingers' tips to its thumb's."""
    op, data = plan_steps_on(TASK, EMBODIMENT, [step])
    looks_with_object_under_wrist(op, data, "green_piece", ("set_off",))
    frames = op.sides["right"]["timeline"].frames
    ease, opened = frames[-3], frames[-4]       # from the end: back home, retreat, ease off, open
    ready = flat_pinch(op, data, op.scene.task.demo_plan[0], "green_piece")[1]
    axis = quat_to_mat(opened.quat) @ tip_axis("sharpa", ready)
    away = -np.array([axis[0], axis[1], 0.0]) / np.linalg.norm(axis[:2])
    return np.array([*(ease.pos - opened.pos)[:2], 0.0]), away


def test_ease_turned_is_a_flat_pinchs_only():
    step = {**GREEN, "grasp": "power", "ease_turned": True}
    del step["grasp_yaw"]
    with pytest.raises(SpecError, match=r"field 'demo_plan\[0\]\.ease_turned'.*no ease_turned without grasp: flat_pinch"):
        parse_steps(TASK, [step])


def test_ease_turned_slides_off_the_thumbs_side_of_the_turned_hand():
    # place_yaw 0: the hand turned about a quarter from how it took the piece (tips closing along y at the grasp)
    turned = {**GREEN, "place_yaw": 0}
    move, away = _ease_and_away({**turned, "ease_turned": True})
    assert np.allclose(move, EASE_M * away, atol=1e-9)
    move, away = _ease_and_away(turned)         # default: the direction planned before the turn
    assert np.linalg.norm(move) == pytest.approx(EASE_M, abs=1e-9)
    assert float(move @ away) / EASE_M < np.cos(np.radians(45))
