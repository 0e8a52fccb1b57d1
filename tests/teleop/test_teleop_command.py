"""Retargeted hands + arm IK -> one joint-position command, driven through the sanitizer, on a
simulated embodiment (floor + bimanual robot)."""

from __future__ import annotations

import functools

import mujoco
import numpy as np

import sim.physics as physics
from sim.embodiment import add_bimanual_robot
from sim.embodiment.description import Transform, mat_to_quat, rpy_to_matrix
from teleop.retarget import TeleopCommander
from teleop.streams import OperatorFrame, StepFlag, StreamSanitizer
from teleop.streams.human_hand import open_hand, pinch

EMBODIMENT = "ur5_rh5dg2"
PERIOD = 16_666_667
ANCHOR = Transform(np.array([0.3, -0.2, 1.1]), rpy_to_matrix([0.3, -0.5, 1.0]))     # tracker frame
MOVE = Transform(np.array([0.05, -0.03, 0.04]), rpy_to_matrix([0.15, -0.2, 0.1]))    # in the hand frame


@functools.lru_cache(maxsize=None)
def robot(name: str):
    spec = mujoco.MjSpec()
    physics.configure_options(spec)
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[3, 3, 0.1])
    layout = add_bimanual_robot(spec, name)
    return spec.compile(), layout


def frame(i: int, wrist: Transform, keypoints=None) -> OperatorFrame:
    f = OperatorFrame.empty(i * PERIOD)
    for side in ("left", "right"):
        kp = open_hand(side) if keypoints is None else keypoints(side)
        f = f.with_hand(side, keypoints=kp, wrist_pos=wrist.pos, wrist_quat=mat_to_quat(wrist.rot))
    return f


def moved(s: float) -> Transform:
    """The operator's wrist a fraction s of the way along MOVE (hand frame)."""
    return ANCHOR @ Transform(MOVE.pos * s, rpy_to_matrix(np.array([0.15, -0.2, 0.1]) * s))


def session():
    model, layout = robot(EMBODIMENT)
    data = mujoco.MjData(model)
    layout.apply_home(model, data)
    commander, sanitizer = TeleopCommander(model, layout), StreamSanitizer(PERIOD)
    ctrl = commander.reset()
    for _ in range(physics.HOMING_STEPS):
        physics.step_control(model, data, ctrl)
    return model, layout, data, commander, sanitizer


def test_a_wrist_pose_from_the_stream_moves_the_simulated_wrist_there():
    model, layout, data, commander, sanitizer = session()
    first = commander.command(sanitizer.step(frame(0, ANCHOR)))
    assert first.flags == StepFlag.NONE
    assert np.allclose(first.ctrl[layout.actuator_ids(model)][:6], layout.home_ctrl[:6], atol=1e-6)  # anchor = home
    for k in range(1, 300):         # 40 steps along the way, then hold and let it settle
        step = commander.command(sanitizer.step(frame(k, moved(min(1.0, k / 40)))))
        assert step.flags == StepFlag.NONE, step.reasons
        physics.step_control(model, data, step.ctrl)
    for side in ("left", "right"):
        s = commander.sides[side]
        target = s.base_home @ MOVE @ s.site_in_base        # independent of the commander's bookkeeping
        sid = model.site(layout.sides[side].wrist_site).id
        pos, R = data.site_xpos[sid], data.site_xmat[sid].reshape(3, 3)
        assert np.linalg.norm(pos - s.kin.fk(s.home_arm)[0]) > 0.05          # it really moved
        assert np.linalg.norm(pos - target.pos) < 2e-3
        angle = np.degrees(np.arccos(np.clip((np.trace(R.T @ target.rot) - 1) / 2, -1, 1)))
        assert angle < 2.0


def test_hand_targets_are_the_retargeted_joints_in_actuator_order():
    model, layout, data, commander, sanitizer = session()
    for k in range(6):
        cmd = commander.command(sanitizer.step(frame(k, ANCHOR, keypoints=lambda side: pinch(side=side))))
    for side in ("left", "right"):
        ids = [model.actuator(a).id for a in layout.sides[side].hand_actuators]
        q = cmd.ctrl[ids]
        assert np.array_equal(q, commander.sides[side].hand_q)
        lo, hi = model.actuator_ctrlrange[ids].T
        assert np.all(q >= lo) and np.all(q <= hi) and not np.allclose(q, commander.sides[side].home_hand)


def test_unreachable_wrist_pose_holds_the_last_arm_target():
    model, layout, data, commander, sanitizer = session()
    commander.command(sanitizer.step(frame(0, ANCHOR)))
    good = commander.command(sanitizer.step(frame(1, moved(0.2))))
    far = ANCHOR @ Transform(np.array([0.0, 0.0, 3.0]), np.eye(3))         # 3 m along the fingers
    bad = commander.command(sanitizer.step(frame(2, far)))
    assert bad.flags == StepFlag.UNREACHABLE
    assert sum("unreachable" in r for r in bad.reasons) == 2
    arm = [model.actuator(a).id for s in ("left", "right") for a in layout.sides[s].arm_actuators]
    assert np.array_equal(bad.ctrl[arm], good.ctrl[arm])
    back = commander.command(sanitizer.step(frame(3, moved(0.25))))         # the session carries on
    assert back.flags == StepFlag.NONE and not np.array_equal(back.ctrl[arm], good.ctrl[arm])


def test_bad_input_and_reset_keep_the_command_well_formed():
    model, layout, data, commander, sanitizer = session()
    before = commander.command(sanitizer.step(None))
    assert before.flags & StepFlag.NO_INPUT_YET and np.array_equal(before.ctrl, commander.home_ctrl)
    commander.command(sanitizer.step(frame(1, ANCHOR)))
    moving = commander.command(sanitizer.step(frame(2, moved(0.3))))
    nan = frame(3, moved(0.6))
    nan.keypoints[1, 4] = np.nan
    nan.wrist_pos[0, 2] = np.nan
    held = commander.command(sanitizer.step(nan))
    assert held.flags == StepFlag.BAD_KEYPOINTS | StepFlag.BAD_WRIST
    right_hand = [model.actuator(a).id for a in layout.sides["right"].hand_actuators]
    left_arm = [model.actuator(a).id for a in layout.sides["left"].arm_actuators]
    assert np.array_equal(held.ctrl[right_hand], moving.ctrl[right_hand])
    assert np.array_equal(held.ctrl[left_arm], moving.ctrl[left_arm])
    assert np.all(np.isfinite(held.ctrl))
    # reset: home command, and the next wrist pose becomes the new anchor (the robot stays home)
    assert np.array_equal(commander.reset(), commander.home_ctrl)
    sanitizer.reset()
    again = commander.command(sanitizer.step(frame(0, moved(0.6))))
    arm = [model.actuator(a).id for s in ("left", "right") for a in layout.sides[s].arm_actuators]
    assert np.allclose(again.ctrl[arm], commander.home_ctrl[arm], atol=1e-6)


def test_a_session_replays_to_identical_commands():
    outputs = []
    for _ in range(2):
        model, layout, data, commander, sanitizer = session()
        seq = [frame(k, moved(k / 10), keypoints=lambda side, k=k: (1 - k / 10) * open_hand(side) + k / 10 * pinch(side=side))
               for k in range(10)]
        seq[4] = None
        outputs.append(np.array([commander.command(sanitizer.step(f)).ctrl for f in seq]))
    assert outputs[0].tobytes() == outputs[1].tobytes()
