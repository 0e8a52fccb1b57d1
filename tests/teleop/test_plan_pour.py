"""Plan step `pour`: its load-time check, its keyframes and a real episode tipping a bottle."""

import dataclasses

import mujoco
import numpy as np
import pytest

from sim import physics
from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task
from teleop.operator_motion import axis_rotation, quat
from teleop.plan_steps.pour import POUR_DURATIONS, mouth_local
from plan_runs import home_and_plan

TASK, EMBODIMENT = "frypan_stand_pour", "ur5_schunk"
MIN_TILT_DEG, RADIUS_M = 50.0, 0.12          # the task's tilted_over stage
STEP = {"hand": "right", "pour": "soy_sauce", "into": "stand"}   # clear of the other arm


def _check(**fields):
    task = load_task(TASK)
    return parse_plan("t.yaml", {"demo_plan": [{**STEP, **fields}]}, PlanScope(task.objects, task.zones, task.points))


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
    ({"grasp_yaw": "across"}, "grasp_yaw"),      # a bottle has no narrow side: degrees only
    ({"grasp_yaw": 200}, "grasp_yaw"),
    ({"grasp_point": [0.0, 0.03]}, "grasp_point"),
    ({"grasp": "pinch", "grasp_point": [0.0, 0.0, 0.03]}, "grasp_point"),
])
def test_check_refuses_bad_fields(fields, field):
    with pytest.raises(SpecError, match=rf"demo_plan\[0\]\.{field}"):
        _check(**fields)


def test_check_accepts_a_pour():
    assert _check(tilt_deg=90, grasp="side", place_offset=[0.3, -0.1])[0]["pour"] == "soy_sauce"
    assert _check(grasp_yaw=-30, grasp_point=[0.005, 0.0, 0.03])[0]["grasp_yaw"] == -30


def _operator(step):
    scene = demonstration_scene(TASK, EMBODIMENT, 0)
    scene.task = dataclasses.replace(scene.task, demo_plan=_check(**step))    # a copy: the cached task keeps its plan
    data, op = home_and_plan(scene)
    return scene, data, op


def _tilt_and_reach(scene, pos, R, target_xy, name="soy_sauce"):
    obj = scene.task.objects[name]
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


def test_grasp_yaw_and_grasp_point_move_the_side_grasp():
    """grasp_yaw turns the side grasp about the vertical; grasp_point raises where the hand closes."""
    scene, data, _ = _operator({})
    base = _operator({})[2].sides["right"]["timeline"].frames[2]        # descended, about to close
    turned = _operator({"grasp_yaw": -30})[2].sides["right"]["timeline"].frames[2]
    yaw = np.array([[np.cos(-np.pi / 6), -np.sin(-np.pi / 6), 0.0], [np.sin(-np.pi / 6), np.cos(-np.pi / 6), 0.0],
                    [0.0, 0.0, 1.0]])
    assert np.allclose(_mat(turned.quat), yaw @ _mat(base.quat), atol=1e-6)
    raised = _operator({"grasp_point": [0.0, 0.0, 0.03]})[2].sides["right"]["timeline"].frames[2]
    lift = (data.xmat[scene.object_body_ids["soy_sauce"]].reshape(3, 3) @ [0.0, 0.0, 0.03])[2]
    assert raised.pos[2] - base.pos[2] == pytest.approx(lift, abs=1e-6)


def test_look_after_the_untilt_turns_the_bottle_upright_by_the_bottle():
    """Held from the side, a bottle turns in the grip while tipped (20 degrees here): the look after
    the untilt turns the hand so that the bottle, as it now sits in it, stands upright, and moves the
    set-down keyframes so that its centre still goes where it was to go."""
    scene, data, op = _operator({})
    side = op.sides["right"]
    frames = side["timeline"].frames
    when, adjust = side["looks"][0]
    first = next(i for i, f in enumerate(frames) if f.end_step > when)      # the keyframes after the look
    planned = [(f.pos.copy(), _mat(f.quat)) for f in frames[first:-1]]
    grasp = frames[2]
    body = scene.object_body_ids["soy_sauce"]
    in_hand = _mat(grasp.quat).T @ data.xmat[body].reshape(3, 3)
    offset = _mat(grasp.quat).T @ (data.xpos[body] - grasp.pos)
    # the bottle in the hand as it was held, then turned 20 degrees in the grip (about its own x)
    turn = axis_rotation(np.array([1.0, 0.0, 0.0]), np.radians(20.0))
    wrist_rot = data.site_xmat[side["wrist_site_id"]].reshape(3, 3)
    adr = scene.model.jnt_qposadr[scene.model.body_jntadr[body]]
    data.qpos[adr:adr + 3] = data.site_xpos[side["wrist_site_id"]] + wrist_rot @ offset
    data.qpos[adr + 3:adr + 7] = quat(wrist_rot @ in_hand @ turn)
    mujoco.mj_forward(scene.model, data)
    held = wrist_rot.T @ data.xmat[body].reshape(3, 3)
    at = wrist_rot.T @ (data.xpos[body] - data.site_xpos[side["wrist_site_id"]])
    axis = np.asarray(scene.task.objects["soy_sauce"].mouth_axis, float)
    assert (planned[0][1] @ held @ axis)[2] < np.cos(np.radians(15.0))     # as planned: set down tilted
    adjust(data)
    for (pos, R), frame in zip(planned, frames[first:-1]):
        R_new = _mat(frame.quat)
        assert (R_new @ held @ axis)[2] > np.cos(np.radians(1.0))
        # where the bottle's centre goes with the hand at this keyframe: as planned
        assert frame.pos + R_new @ at == pytest.approx(pos + R @ offset, abs=1e-6)


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


# pouring over a task point (the evaluator's target may be a point): the toilet task's pour point in its bowl
POINT_TASK, POINT_EMBODIMENT, POINT = "toilet_lid_cleaner_pour", "xarm7_leap", "bowl_left"
POINT_STEP = {"hand": "left", "pour": "cleaner", "into": POINT, "grasp": "side", "tilt_toward": [1.0, 0.0]}


def _check_point(**fields):
    task = load_task(POINT_TASK)
    return parse_plan("t.yaml", {"demo_plan": [{**POINT_STEP, **fields}]},
                      PlanScope(task.objects, task.zones, task.points))


def test_check_refuses_an_unknown_point_naming_objects_and_points():
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.into.*an object from \['toilet'\] or a point from "
                                        r"\['bowl_centre', 'bowl_left'\]"):
        _check_point(into="cistern")
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.into"):
        _check_point(into=["bowl_centre"])


def test_check_accepts_a_point():
    assert _check_point()[0]["into"] == POINT


def _point_operator():
    scene = demonstration_scene(POINT_TASK, POINT_EMBODIMENT, 0)
    scene.task = dataclasses.replace(scene.task, demo_plan=_check_point())
    data, op = home_and_plan(scene)
    # the point as the evaluator resolves it: its z is from the table top
    point = np.asarray(scene.task.points[POINT], float) + [0.0, 0.0, scene.table_height]
    return scene, data, op, point


def _mat(q):
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, q)
    return R.reshape(3, 3)


def test_keyframes_tip_the_mouth_just_above_a_point():
    """The most tipped keyframe holds the cleaner's mouth over the point in xy, tilted well past the
    threshold, and above the point (not in the bowl's rim) by no more than a hand's width."""
    scene, data, op, point = _point_operator()
    side = op.sides["left"]
    frames = side["timeline"].frames
    body = scene.object_body_ids["cleaner"]
    obj = scene.task.objects["cleaner"]
    grasp = frames[2]                          # descended, about to close: the bottle as it will be held
    in_hand = _mat(grasp.quat).T @ data.xmat[body].reshape(3, 3)
    offset = _mat(grasp.quat).T @ (data.xpos[body] - grasp.pos)
    poses = [(f, _mat(f.quat)) for f in frames[3:-1]]     # held (not the home poses: a side grasp's bottle would lie flat)
    tilted, R = max(poses, key=lambda p: -(p[1] @ in_hand @ np.asarray(obj.mouth_axis, float))[2])
    tilt, dist = _tilt_and_reach(scene, tilted.pos + R @ offset, R @ in_hand, point[:2], "cleaner")
    mouth = tilted.pos + R @ offset + R @ in_hand @ mouth_local(obj)
    assert tilt >= MIN_TILT_DEG + 20 and dist <= RADIUS_M / 4
    assert 0.0 < mouth[2] - point[2] <= 0.1, f"mouth {mouth[2] - point[2]:.3f} m above the point"
    assert side["kin"].ik(tilted.pos, tilted.quat, side["q"]).success


def test_episode_tips_the_bottle_over_a_point():
    scene, data, op, point = _point_operator()
    body = scene.object_body_ids["cleaner"]
    frames = op.sides["left"]["timeline"].frames
    pour_end = frames[-7].end_step       # ... tilt, pour; then untilt, back, lower, release (2), rise, home
    poured = 0
    for step in range(pour_end):
        physics.step_control(scene.model, data, op.act(step, data))
        tilt, dist = _tilt_and_reach(scene, data.xpos[body], data.xmat[body].reshape(3, 3), point[:2], "cleaner")
        poured += tilt >= MIN_TILT_DEG and dist <= RADIUS_M
    assert poured >= POUR_DURATIONS["pour"] // 2
