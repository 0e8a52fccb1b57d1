"""The stream path closes the hand as the plan commands.

DexPilot reads a thumb tip within ``project_dist`` of a finger's as a pinch and pulls the two tips
together at weight 200. With the live 3 cm (human scale) that fired on grasps whose tips the plan
keeps apart: the RH5DG2's power grasp (fingers curled past the thumb) ended 0.38 rad short of its
1.32 rad, the Revo2's flat pinch 0.24 rad off. The scripted person's ``SCRIPTED_RETARGET`` pinches only
where the plan's pads meet; on the hands whose fingertips fix their joints the command is then the plan's.
"""

from __future__ import annotations

import numpy as np
import pytest

from sim.embodiment import load_hand
from sim.scene.builder import demonstration_scene
from teleop.flat_pinch import tip_pinch
from teleop.pinch_grasp import pinch_grasp
from teleop.recorder import home
from teleop.retarget import DexPilotRetargeter
from teleop.scripted_operator import CLOSED_FRACTION, hand_grasp
from teleop.scripted_stream import LIVE_PINCH_RETARGET, SCRIPTED_RETARGET, RobotShapedHand, ScriptedStreamOperator
from teleop.streams import OperatorFrame
from teleop.streams.frame import SIDES

# hands whose fingertips fix their joints (one flexion chain per fingertip): DexPilot can only
# return the plan's joints there. The others pick their own split between a finger's joints.
DETERMINED = ("ability", "dexhand021", "revo2", "rh56dfx", "rh5dg2", "schunk_svh")
JOINT_TOLERANCE_RAD = 0.01
RAMP, HOLD = 60, 30


def power_closed(hand: str, kin) -> np.ndarray:
    """The scripted operator's power grasp (``ScriptedOperator``'s ``closed``), in actuator order."""
    far = np.where(np.abs(kin.upper - kin.home) >= np.abs(kin.lower - kin.home), kin.upper, kin.lower)
    closed = kin.home + CLOSED_FRACTION * (far - kin.home)
    grasp = hand_grasp(load_hand(hand), "right")
    for i, name in enumerate(kin.actuators):
        if name in grasp.close:
            closed[i] = np.clip(grasp.close[name], kin.lower[i], kin.upper[i])
    return closed


def grasp_pose(hand: str, kin, pose: str) -> np.ndarray:
    if pose == "power":
        return power_closed(hand, kin)
    close = pinch_grasp(hand).close if pose == "pinch" else tip_pinch(hand).close
    return np.clip(close, kin.lower, kin.upper)


def close_through_stream(hand: str, target: np.ndarray, config=SCRIPTED_RETARGET, side: str = "right"):
    """Open -> ``target`` along a smoothstep, then held: the scripted person's keypoints (with their
    lead over the filters) retargeted frame by frame. Returns the last command and the retargeter."""
    op = ScriptedStreamOperator(config)
    rt = DexPilotRetargeter(hand, config)
    op.hand = RobotShapedHand(rt.kin)
    start = rt.kin.home.copy()
    for k in range(RAMP + HOLD):
        s = min(k / RAMP, 1.0)
        q = rt.retarget(op._lead(side, start + s * s * (3 - 2 * s) * (target - start)), side)
    return q, rt


@pytest.mark.parametrize("pose", ["power", "pinch", "flat"])
@pytest.mark.parametrize("hand", DETERMINED)
def test_the_stream_closes_as_the_plan_commands(hand, pose):
    kin = DexPilotRetargeter(hand).kin
    target = grasp_pose(hand, kin, pose)
    got, _ = close_through_stream(hand, target)
    error = np.abs(got - target)
    worst = int(np.argmax(error))
    assert error.max() < JOINT_TOLERANCE_RAD, (
        f"{hand} {pose}: {kin.actuators[worst]} commanded {got[worst]:.3f} rad, the plan {target[worst]:.3f}")


def test_the_live_pinch_rule_opens_the_rh5dg2_power_grasp():
    """Why the scripted person's pinch is narrower: at the live 3 cm the power grasp, whose fingers curl
    past the thumb, is read as a pinch and ends far short of the plan."""
    kin = DexPilotRetargeter("rh5dg2").kin
    target = power_closed("rh5dg2", kin)
    got, _ = close_through_stream("rh5dg2", target, LIVE_PINCH_RETARGET)
    assert np.abs(got - target).max() > 0.3


@pytest.mark.parametrize("hand", ["rh5dg2", "wuji"])
def test_a_pinch_whose_pads_meet_is_still_a_pinch(hand):
    """The pad pinch (pads meeting) is read as a pinch, thumb to each pinching finger (the tripod's
    two fingers too)."""
    grasp = pinch_grasp(hand)
    _, rt = close_through_stream(hand, grasp_pose(hand, DexPilotRetargeter(hand).kin, "pinch"))
    fingers = [t.finger for t in rt.kin.spec.fingertips[1:]]
    pinched = {fingers[k] for k in np.flatnonzero(rt.projected[: rt.n_s1])}
    assert pinched == set(grasp.fingers), f"{hand}: pinch read on {sorted(pinched)}, the plan pinches {grasp.fingers}"


def test_the_commander_closes_both_rh5dg2_hands_as_the_plan():
    """Frames built by the scripted stream for a held power grasp, through the live session's
    sanitizer and TeleopCommander on the UR5+RH5DG2 scene: both hands' commands are the plan's
    (the bottle-neck grasp that lifted on direct joints only: fingers 1.32 rad, thumb bend 0.45)."""
    scene = demonstration_scene("citrus_plate_loading", "ur5_rh5dg2")
    data = home(scene)
    op = ScriptedStreamOperator()
    op.reset(scene, data)
    kin = op.hand.kin
    target = power_closed("rh5dg2", kin)
    for step in range(RAMP + HOLD):
        s = min(step / RAMP, 1.0)
        q = kin.home + s * s * (3 - 2 * s) * (target - kin.home)
        now = step * op.sanitizer.nominal_period_ns
        frame = OperatorFrame.empty(now)
        for side in SIDES:
            frame = frame.with_hand(side, op._lead(side, q), *home_wrist(op, side))
        cmd = op.commander.command(op.sanitizer.step(frame, now))
        assert cmd.flags == 0, cmd.reasons
    for side in SIDES:
        got = cmd.ctrl[op.commander.sides[side].hand_ids]
        assert np.abs(got - target).max() < JOINT_TOLERANCE_RAD, f"{side}: commanded {np.round(got, 3)}, plan {target}"


def home_wrist(op: ScriptedStreamOperator, side: str):
    """The operator's wrist where the robot hand's base is at home (the commander's anchor)."""
    base = op.commander.sides[side].base_home
    return base.pos, base.quat
