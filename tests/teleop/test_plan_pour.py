"""Plan step `pour`: its load-time check, its keyframes and a real episode tipping a bottle."""

import mujoco
import numpy as np
import pytest

from sim import physics
from sim.demo_plan import parse_plan
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task
from teleop.plan_steps.pour import POUR_DURATIONS, mouth_local
from teleop.recorder import home
from teleop.scripted_operator import ScriptedOperator

TASK, EMBODIMENT = "frypan_stand_pour", "ur5_schunk"
MIN_TILT_DEG, RADIUS_M = 50.0, 0.12          # the task's tilted_over stage
STEP = {"hand": "right", "pour": "soy_sauce", "into": "stand"}   # clear of the other arm


def _check(**fields):
    task = load_task(TASK)
    return parse_plan("t.yaml", {"demo_plan": [{**STEP, **fields}]}, task.objects, task.zones)


@pytest.mark.parametrize("fields, field", [
    ({"pour": "bread"}, "pour"),                 # no mouth_axis: not a pourer
    ({"into": "soy_sauce"}, "into"),             # into itself
    ({"into": "sink"}, "into"),
    ({"tilt_deg": 30}, "tilt_deg"),              # below any pour threshold
    ({"tilt_deg": True}, "tilt_deg"),
    ({"grasp": "hook"}, "grasp"),
    ({"place_offset": [0.1, 0.1, 0.0]}, "place_offset"),   # a table spot: [x, y]
    ({"approach_pitch_deg": 95}, "approach_pitch_deg"),
    ({"spill": True}, "spill"),
])
def test_check_refuses_bad_fields(fields, field):
    with pytest.raises(SpecError, match=rf"demo_plan\[0\]\.{field}"):
        _check(**fields)


def test_check_accepts_a_pour():
    assert _check(tilt_deg=90, grasp="side", place_offset=[0.3, -0.1])[0]["pour"] == "soy_sauce"


def _operator(step):
    scene = demonstration_scene(TASK, EMBODIMENT, 0)
    scene.task.demo_plan[:] = _check(**step)
    data = home(scene)
    op = ScriptedOperator()
    op.reset(scene, data)
    return scene, data, op


def _tilt_and_reach(scene, pos, R, target_xy):
    obj = scene.task.objects["soy_sauce"]
    up = R @ np.asarray(obj.mouth_axis, float)
    mouth = pos + R @ mouth_local(obj)
    return np.degrees(np.arccos(np.clip(up[2], -1.0, 1.0))), float(np.linalg.norm(mouth[:2] - target_xy))


def test_keyframes_tip_the_mouth_over_the_target():
    scene, data, op = _operator({})
    side = op.sides["right"]
    frames = side["timeline"].frames
    body = scene.object_body_ids["soy_sauce"]
    grasp = frames[2]                          # descended, about to close: the bottle as it will be held
    R_grasp = np.zeros(9)
    mujoco.mju_quat2Mat(R_grasp, grasp.quat)
    R_grasp = R_grasp.reshape(3, 3)
    in_hand = R_grasp.T @ data.xmat[body].reshape(3, 3)
    offset = R_grasp.T @ (data.xpos[body] - grasp.pos)
    tilted = frames[8]          # approach, descend, close (2), hold, lift, to target, tilt
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, tilted.quat)
    R = R.reshape(3, 3)
    tilt, dist = _tilt_and_reach(scene, tilted.pos + R @ offset, R @ in_hand,
                                 data.xpos[scene.object_body_ids["stand"]][:2])
    assert tilt >= MIN_TILT_DEG + 20 and dist <= RADIUS_M / 2
    assert side["kin"].ik(tilted.pos, tilted.quat, side["q"]).success      # the arm reaches the turn
    # tipped back upright before it goes home: the last keyframes hold the grasp's orientation
    assert abs(np.dot(frames[-4].quat, grasp.quat)) > 0.999


def test_episode_tips_the_bottle_over_the_target():
    scene, data, op = _operator({})
    target = data.xpos[scene.object_body_ids["stand"]][:2].copy()
    body = scene.object_body_ids["soy_sauce"]
    pour_end = op.sides["right"]["timeline"].frames[9].end_step     # lift, to target, tilt, pour
    poured = 0
    for step in range(pour_end):
        physics.step_control(scene.model, data, op.act(step, data))
        tilt, dist = _tilt_and_reach(scene, data.xpos[body], data.xmat[body].reshape(3, 3), target)
        poured += tilt >= MIN_TILT_DEG and dist <= RADIUS_M
    assert poured >= POUR_DURATIONS["pour"] // 2     # held over the target, well past the dwell
