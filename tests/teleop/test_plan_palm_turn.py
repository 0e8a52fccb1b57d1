"""`turn` with `palm_from` (the flat palm pushes, fingers along the hinge) and the `wait_s` field every
step kind takes: the checks refuse bad values, naming the field; the closing push of a toilet lid puts
the palm square to the lid, the fingers along its hinge; `wait_s` holds a step back exactly that long;
and in real episodes fingertips-then-palm flip the lid open onto its stop, and a palm pushes the open
lid back over so that it falls shut."""

import mujoco
import numpy as np
import pytest
import yaml

from sim.errors import SpecError
from sim.physics import CONTROL_HZ
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task, parse_task
from sim import physics
from teleop.demos import DEFAULT_OPERATOR, OPERATORS
from teleop.plan_steps.palm_push import palm_frame, palm_turns
from teleop.plan_steps.turn import Hinge
from teleop.recorder import home
from plan_runs import home_and_plan

TASK, EMBODIMENT, LID = "toilet_lid_cleaner_pour", "xarm7_leap", "toilet/lid"
OPEN, CLOSE = 0, 2          # the plan's steps that turn the lid
# The layout these palm-push tests were tuned on, an earlier one than the task file's (whose plan holds the
# cleaner from the side, tests/teleop/test_plan_pour_tilt_toward.py): the toilet turned so its hinge is on the
# right (hinged at the back, the open lid's far face is beyond both xArm7s) but nearer the arms, the cleaner
# back out of the lifting hand's way, a pour point in the bowl's left half. The lid's tab and its open stop
# 5 deg past vertical are the task file's.
PLAN = [
    {"hand": "left", "turn": LID, "to": 1.6, "palm_from": 1.2},
    {"hand": "left", "pour": "cleaner", "into": "bowl_left", "grasp": "pinch", "after": [0]},
    {"hand": "right", "turn": LID, "to": 1.4, "palm_from": 1.65, "after": [0], "wait_s": 7.0},
]


def _raw(plan=PLAN):
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    toilet = raw["objects"]["toilet"]
    toilet["pose"] = {"xy": [0.0, 0.1], "yaw_deg": -90}
    raw["objects"]["cleaner"]["pose"] = {"xy": [-0.4, 0.16]}
    raw["points"] = {"bowl_centre": [-0.06, 0.1, 0.18], "bowl_left": [-0.125, 0.1, 0.18]}
    raw["demo_plan"] = [dict(step) for step in plan]
    return raw


@pytest.mark.parametrize("value", [1.8, -0.1, "open", True, None])
def test_palm_from_must_be_an_angle_in_the_joint_range(tmp_path, value):
    raw = _raw()
    raw["demo_plan"][0]["palm_from"] = value
    with pytest.raises(SpecError, match=r"toilet.yaml: field 'demo_plan\[0\].palm_from'.*within the joint range \[0, 1.65\]"):
        parse_task(raw, tmp_path / "toilet.yaml")


@pytest.mark.parametrize("value", [-1.0, 61.0, "soon", False, [1]])
def test_wait_s_must_be_seconds(tmp_path, value):
    raw = _raw()
    raw["demo_plan"][1]["wait_s"] = value       # a pour: every kind takes it
    with pytest.raises(SpecError, match=r"toilet.yaml: field 'demo_plan\[1\].wait_s'.*seconds in \[0, 60\]"):
        parse_task(raw, tmp_path / "toilet.yaml")


def test_palm_frame_faces_the_push_with_the_fingers_square_to_it():
    push = np.array([0.6, 0.0, 0.8])
    R = palm_frame(push, np.array([0.1, 1.0, 0.0]))
    assert np.allclose(R.T @ R, np.eye(3)) and np.isclose(np.linalg.det(R), 1.0)
    assert np.allclose(R[:, 1], push)                       # the palm normal (wrist-site y)
    assert abs(R[:, 2] @ push) < 1e-12 and R[:, 2][1] > 0.99 * np.linalg.norm(R[:, 2][:2])


def test_palm_turns_from_its_angle_on_either_way():
    assert not palm_turns(1.0, None, 1.0)
    assert palm_turns(1.2, 1.2, 1.0) and palm_turns(1.5, 1.2, 1.0) and not palm_turns(1.1, 1.2, 1.0)
    assert palm_turns(1.65, 1.65, -1.0) and palm_turns(1.4, 1.65, -1.0) and not palm_turns(1.5, 1.4, -1.0)


def _planned(raw, tmp_path):
    task = parse_task(raw, tmp_path / "toilet.yaml")
    scene = demonstration_scene(task, EMBODIMENT)
    data, op = home_and_plan(scene)
    return scene, data, op


def test_closing_push_is_the_palm_square_to_the_lid_and_wait_s_holds_the_step_back(tmp_path):
    raw = _raw()
    scene, data, op = _planned(raw, tmp_path)
    link = Hinge(scene.model, data, LID)
    close = raw["demo_plan"][2]
    assert close["hand"] == "right" and "palm_from" in close and close["wait_s"] > 0
    right = op.sides["right"]["timeline"].frames
    # the right hand's first keyframe holds it at home until step 0 ends plus wait_s; its pressing
    # keyframes (between the approach-descent and the draw-back) have the palm normal along the way
    # the lid's outer face moves as it shuts, and the fingers along the hinge
    hold_end = right[1].end_step
    pressing = right[4:-5]
    assert pressing
    for frame in pressing:
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, frame.quat)
        R = R.reshape(3, 3)
        assert abs(R[:, 2] @ link.axis) > 0.99
        assert R[:, 1] @ np.array([-1.0, 0.0, 0.0]) > 0.9      # the lid shuts towards -x (hinge on the right)
    wait = raw["demo_plan"][2].pop("wait_s")
    _, _, op0 = _planned(raw, tmp_path)
    assert hold_end - op0.sides["right"]["timeline"].frames[1].end_step == round(wait * CONTROL_HZ)


def _lid_after(raw, tmp_path, lid_start: float | None = None) -> float:
    """The lid's angle once the scripted operator has played ``raw``'s plan through the stream interface
    (what recordings use), from the lid at ``lid_start`` (None: shut, as the scene starts)."""
    task = parse_task(raw, tmp_path / "toilet.yaml")
    scene = demonstration_scene(task, EMBODIMENT)
    data = home(scene)
    adr = scene.joint_qpos_adr[LID]
    if lid_start is not None:
        data.qpos[adr] = lid_start
        mujoco.mj_forward(scene.model, data)
    op = OPERATORS[DEFAULT_OPERATOR]()
    op.reset(scene, data)
    for step in range(op.plan.length):
        physics.step_control(scene.model, data, op.act(step, data))
    return float(data.qpos[adr])


def test_fingertips_then_palm_open_the_lid_onto_its_stop(tmp_path):
    """Lifted by the tab with one fingertip, then pushed past vertical by the flat palm: the lid ends on
    its open stop (gravity holds it there), not back on the bowl."""
    assert _lid_after(_raw([PLAN[OPEN]]), tmp_path) > 1.6


def test_the_palm_pushes_the_open_lid_back_over_and_it_falls_shut(tmp_path):
    close = {k: v for k, v in PLAN[CLOSE].items() if k not in ("after", "wait_s")}
    assert _lid_after(_raw([close]), tmp_path, lid_start=1.65) < 0.1
