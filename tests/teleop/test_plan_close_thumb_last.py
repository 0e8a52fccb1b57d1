"""Pick field `close_thumb_last` (power grasp): the fingers close first and form a wall, then the thumb's
actuators (those that move its tip) press the object against it, whatever the hand file's `late`. The
Wuji's palm-down grasp closes the thumb with the fingers (its `late` is empty: an upright bottle needs it
so), and on citrus_plate_loading its thumb reached the 5.4 cm lemon first and flicked it out on the lift;
with the thumb last both fruit are lifted. The check refuses the field off a power grasp; without the field
nothing changes."""

import dataclasses

import numpy as np
import pytest

from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task
from teleop.pinch_grasp import thumb_actuators
from teleop.recorder import home
from teleop.scripted_operator import ScriptedOperator

TASK, EMBODIMENT, HAND = "citrus_plate_loading", "ur5_wuji", "wuji"
PICK = {"hand": "right", "pick": "lemon_1", "place": "plate", "place_offset": [0.065, -0.07]}


def _plan(steps):
    task = load_task(TASK)
    return parse_plan("t.yaml", {"demo_plan": steps}, PlanScope(task.objects, task.zones, task.points))


def _right_hand_targets(step: dict) -> tuple[list[np.ndarray], dict]:
    """The right hand's keyframe targets, and its side of the operator."""
    scene = demonstration_scene(TASK, EMBODIMENT, 0)
    scene.task = dataclasses.replace(scene.task, demo_plan=_plan([step]))     # not load_task's cached one
    op = ScriptedOperator()
    op.reset(scene, home(scene))
    side = op.sides["right"]
    return [np.asarray(f.hand, float) for f in side["timeline"].frames], side


@pytest.mark.parametrize("fields", [{"grasp": "pinch"}, {"grasp": "side"}, {"close_thumb_last": "yes"}])
def test_check_refuses_close_thumb_last_off_a_power_grasp(fields):
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.close_thumb_last"):
        _plan([{**PICK, "close_thumb_last": True, **fields}])


def test_the_thumb_actuators_are_the_thumbs_joints():
    assert thumb_actuators(HAND).sum() == 4 and thumb_actuators(HAND)[:4].all()
    assert thumb_actuators("rh5dg2").tolist() == [True, True, False, False, False, False]


def test_the_fingers_close_first_then_the_thumb():
    targets, side = _right_hand_targets({**PICK, "close_thumb_last": True})
    closed, open_, thumb = side["closed"], side["open"], thumb_actuators(HAND)
    wall = next(i for i, q in enumerate(targets) if np.allclose(q[~thumb], closed[~thumb]))
    assert np.allclose(targets[wall][thumb], open_[thumb])      # the fingers' wall, the thumb still open
    assert np.allclose(targets[wall + 1], closed)                # then the thumb closes too
    plain, _ = _right_hand_targets(PICK)      # the hand file's grasp: all together
    assert np.allclose(plain[wall], closed) and len(plain) == len(targets)
