"""`slide_as_held: true` on a `pick` with `place_from: front`: outside the opening the operator looks where the
object sits in the hand and moves the slide with it, but keeps the hand's turn as planned. By default the look
also turns the hand so that the object goes in standing as it stood when picked; a banana lying on its side has
no up, and on fridge_fruit_shelf_sorting, rolled 20-60 degrees in the flat pinch, the turn pitched the UR5+Inspire
hands' fingers down and lifted the wrist links into the shelf's front edge at the mouth (~950 N)."""

import mujoco
import numpy as np
import pytest
import yaml

from sim.errors import SpecError
from sim.scene.parts import quat_matrix
from sim.tasks import load_task, parse_task
from teleop.operator_motion import UP, axis_rotation
from teleop.plan_steps.front_place import RELEASE_GAP_M
from plan_runs import front_slide_look, plan_steps_on

TASK, EMBODIMENT, NAME = "fridge_fruit_shelf_sorting", "ur5_shadow", "banana"
BANANA = {"hand": "right", "pick": "banana", "place": "fridge", "place_from": "front",
          "place_offset": [0.15, -0.14, 0.03], "grasp": "flat_pinch", "slide_fingers_in": True}


def _planned(**fields):
    op, data = plan_steps_on(TASK, EMBODIMENT, [{**BANANA, **fields}])
    return op.scene, data, op



def _look_at_a_rolled_banana(**fields):
    """The plan's slide and let-go frames before and after the look outside the opening, the banana 5 mm lower
    in the hand than planned and rolled 30 degrees about its length; and where it is let go after the look."""
    scene, data, op = _planned(**fields)
    side = op.sides["right"]
    look, slide, lower = front_slide_look(side)
    planned = [(f.pos.copy(), f.quat.copy()) for f in (slide, lower)]
    placed = next(pos for _, name, pos, on in op.moves if name == NAME and on == "fridge") + RELEASE_GAP_M * UP
    hand_rot = quat_matrix(slide.quat)
    at = hand_rot.T @ (placed - lower.pos - 0.005 * UP)            # the banana's centre, wrist frame
    body = scene.object_body_ids[NAME]
    banana = data.xmat[body].reshape(3, 3)
    roll = axis_rotation(banana[:, 0], np.radians(30.0))           # about its length (the capsule's axis: body x)
    in_hand = hand_rot.T @ roll @ banana
    site = side["wrist_site_id"]
    wrist_rot, wrist = data.site_xmat[site].reshape(3, 3), data.site_xpos[site]
    adr = scene.model.jnt_qposadr[scene.model.body_jntadr[body]]
    data.qpos[adr:adr + 3] = wrist + wrist_rot @ at
    mujoco.mju_mat2Quat(data.qpos[adr + 3:adr + 7], (wrist_rot @ in_hand).flatten())
    mujoco.mj_kinematics(scene.model, data)
    look(data)
    let_go = lower.pos + quat_matrix(lower.quat) @ at
    return planned, (slide, lower), let_go, placed


def test_as_held_the_hand_keeps_its_turn_and_the_banana_is_let_go_where_planned():
    planned, looked, let_go, placed = _look_at_a_rolled_banana(slide_as_held=True)
    for (pos, q), frame in zip(planned, looked):
        assert np.allclose(frame.quat, q), "the hand's turn as planned"
        assert not np.allclose(frame.pos, pos), "moved for where the banana sits"
    assert np.allclose(let_go, placed, atol=1e-6), "let go where planned"


def test_by_default_the_rolled_banana_turns_the_hand(tmp_path):
    planned, looked, _, _ = _look_at_a_rolled_banana()
    R0, R1 = quat_matrix(planned[1][1]), quat_matrix(looked[1].quat)
    angle = np.degrees(np.arccos(np.clip((np.trace(R0.T @ R1) - 1) / 2, -1, 1)))
    assert angle == pytest.approx(30.0, abs=1.0), "turned back by the roll"


def test_slide_as_held_only_slides_something_in(tmp_path):
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    raw["demo_plan"] = [{"hand": "right", "pick": "banana", "place": "table", "place_offset": [-0.17, -0.22],
                         "grasp": "flat_pinch", "slide_as_held": True}]
    with pytest.raises(SpecError, match="slide_as_held"):
        parse_task(raw, tmp_path / "fridge.yaml")
