"""Pick field `pinch_fingers` (with `grasp: pinch`): the fingers the thumb's pad closes against, where
the hand's own pinch (teleop/pinch_grasp.py: the first finger set whose pads meet the thumb's) is
not the one the object needs. The DexHand021's own pinch is thumb and index alone, about which a
carried 12 cm mouse turned 20-50 degrees; `[index, middle]` closes the thumb towards both pads (as
near as its thumb reaches them: 7.4 mm, from the mid-range start) and the mouse stays square
(gaming_desk_setup). The check
refuses the field off a pad pinch and fingers that are not fingers; the plan closes to that set's
targets and comes down pre-shaped for it; without the field nothing changes."""

import dataclasses

import numpy as np
import pytest

from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task
from teleop.pinch_grasp import hand_kinematics, pinch_grasp, pinch_rows
from teleop.recorder import home
from teleop.scripted_operator import ScriptedOperator

TASK, EMBODIMENT, HAND = "gaming_desk_setup", "jaka_zu7_dexhand021", "dexhand021"
PICK = {"hand": "right", "pick": "mouse", "place": "table", "place_offset": [-0.08, -0.18], "grasp": "pinch",
        "grasp_yaw": "across"}
TRIPOD = ("index", "middle")


def _plan(steps):
    task = load_task(TASK)
    return parse_plan("t.yaml", {"demo_plan": steps}, PlanScope(task.objects, task.zones, task.points))


def _right_hand_targets(step: dict) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """The right hand's keyframe targets, and its actuators' ranges."""
    scene = demonstration_scene(TASK, EMBODIMENT, 0)
    scene.task = dataclasses.replace(scene.task, demo_plan=_plan([step]))     # not load_task's cached one
    op = ScriptedOperator()
    op.reset(scene, home(scene))
    side = op.sides["right"]
    lo, hi = scene.model.actuator_ctrlrange[side["hand_ids"]].T
    return [np.asarray(f.hand, float) for f in side["timeline"].frames], lo, hi


@pytest.mark.parametrize("fields, where", [
    ({"grasp": "power", "pinch_fingers": ["index"]}, "pinch_fingers"),      # not a pad pinch
    ({"pinch_fingers": ["pinky"]}, "pinch_fingers"),                        # not a finger name
    ({"pinch_fingers": ["index", "index"]}, "pinch_fingers"),               # twice
    ({"pinch_fingers": []}, "pinch_fingers"),
])
def test_check_refuses_pinch_fingers_off_a_pad_pinch_or_not_fingers(fields, where):
    with pytest.raises(SpecError, match=rf"demo_plan\[0\]\.{where}"):
        _plan([{**PICK, **fields}])


def test_the_named_fingers_pinch_the_thumb_where_the_hands_own_pinch_uses_one():
    own, tripod = pinch_grasp(HAND), pinch_grasp(HAND, TRIPOD)
    assert own.fingers == ("index",) and tripod.fingers == TRIPOD
    kin = hand_kinematics(HAND)
    thumb, tips = pinch_rows(HAND, TRIPOD)
    P = kin.points(tripod.close)
    assert max(np.linalg.norm(P[thumb] - P[t]) for t in tips) < 0.01, "both pads close on the thumb's"
    P = kin.points(own.close)
    assert np.linalg.norm(P[thumb] - P[tips[1]]) > 0.02, "the own pinch folds the middle finger away"


def test_the_plan_closes_to_the_named_fingers_and_is_unchanged_without_them():
    plain, lo, hi = _right_hand_targets(PICK)
    tripod, _, _ = _right_hand_targets({**PICK, "pinch_fingers": list(TRIPOD)})
    assert len(plain) == len(tripod)
    own_close, tripod_close = (np.clip(pinch_grasp(HAND, f).close, lo, hi) for f in (None, TRIPOD))
    closed_plain = [i for i, q in enumerate(plain) if np.allclose(q, own_close, atol=1e-6)]
    closed_tripod = [i for i, q in enumerate(tripod) if np.allclose(q, tripod_close, atol=1e-6)]
    assert closed_plain and closed_plain == closed_tripod, "the same keyframes close, each to its own set's pose"
    # the pre-shape it comes down with is the named set's too (a different, wider-apart thumb)
    first = closed_plain[0]
    assert not np.allclose(plain[first - 1], tripod[first - 1])
    # a hand whose own pinch is already index and middle: naming them changes nothing
    assert pinch_grasp("sharpa", TRIPOD).fingers == pinch_grasp("sharpa").fingers
    np.testing.assert_allclose(pinch_grasp("sharpa", TRIPOD).close, pinch_grasp("sharpa").close)
