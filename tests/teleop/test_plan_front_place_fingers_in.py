"""`slide_fingers_in: true` on a `pick` with `place_from: front`: the hand is turned about the vertical on its
way to the opening so that its fingers point straight in; the held object turns with it and is still let go
where planned. On fridge_fruit_shelf_sorting the banana, flat-pinched off the desk, went in with the hand as it
lifted it, fingers pointing across the opening, and the arm's wrist links behind the hand met the open door's
edge and the fridge's side wall at the mouth (the banana was drawn back out: 11 of 12 seeds). Default off: the
hand keeps the turn it lifted the object with."""

import numpy as np
import pytest
import yaml

from sim.errors import SpecError
from sim.scene.parts import quat_matrix
from sim.tasks import load_task, parse_task
from teleop.operator_motion import UP
from teleop.plan_steps.front_place import FINGERS, RELEASE_GAP_M
from plan_runs import plan_steps_on

TASK, EMBODIMENT = "fridge_fruit_shelf_sorting", "ur5_shadow"
BANANA = {"hand": "right", "pick": "banana", "place": "fridge", "place_from": "front",
          "place_offset": [0.15, -0.08, 0.03], "grasp": "flat_pinch"}


def _planned(**fields):
    op, data = plan_steps_on(TASK, EMBODIMENT, [{**BANANA, **fields}])
    return op.scene, data, op



def _slide(op):
    """The frames outside the opening and let go (the hand still closed, then opened)."""
    side = op.sides["right"]
    frames = side["timeline"].frames
    released = next(k for k in range(1, len(frames)) if np.array_equal(frames[k].hand, side["open"])
                    and not np.array_equal(frames[k - 1].hand, side["open"]))
    return frames[released - 3], frames[released - 1]


def test_the_fingers_point_straight_in_and_the_banana_is_let_go_where_planned():
    scene, data, op = _planned(slide_fingers_in=True)
    fridge = scene.object_body_ids["fridge"]
    way_in = data.xmat[fridge].reshape(3, 3)[:, 1]         # the fridge is open at its -y: in is its +y
    outside, lower = _slide(op)
    for frame in (outside, lower):
        fingers = quat_matrix(frame.quat) @ FINGERS
        level = fingers - (fingers @ UP) * UP
        assert level / np.linalg.norm(level) @ way_in == pytest.approx(1.0, abs=1e-6)
    # the banana's centre from the wrist turned with the hand: let go where planned, as without the turn
    _, _, plain = _planned()
    placed = [next(p for _, n, p, on in o.moves if n == "banana" and on == "fridge") for o in (op, plain)]
    assert placed[0] == pytest.approx(placed[1], abs=1e-9)
    assert placed[0][2] + RELEASE_GAP_M > data.xpos[fridge][2] - 0.3, "in the fridge's lower compartment"


def test_default_off_the_hand_keeps_the_turn_it_lifted_with(tmp_path):
    _, _, op = _planned()
    frames = op.sides["right"]["timeline"].frames
    outside, lower = _slide(op)
    lifted = frames[frames.index(outside) - 1]
    assert np.allclose(outside.quat, lifted.quat) and np.allclose(lower.quat, lifted.quat)


def test_only_with_place_from_front(tmp_path):
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    raw["demo_plan"] = [{**{k: v for k, v in BANANA.items() if k != "place_from"}, "place_offset": [0.15, -0.08],
                         "slide_fingers_in": True}]
    with pytest.raises(SpecError, match=r"field 'demo_plan\[0\]\.slide_fingers_in'.*without place_from: front"):
        parse_task(raw, tmp_path / "fridge.yaml")
