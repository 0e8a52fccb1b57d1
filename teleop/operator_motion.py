"""The scripted operator's motion vocabulary: hand orientations, segment durations and heights, and
the per-hand timeline of wrist keyframes and hand targets that the plan steps (teleop/plan_steps/)
append to."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from sim.scene.reach import PALM_DOWN   # fingers pointing away from the robot (+y world)

UP = np.array([0.0, 0.0, 1.0])
FORWARD = np.array([0.0, 1.0, 0.0])   # palm down, the fingers point this way (world)
# Segment durations in control steps (60 Hz). Closing takes as long as the real hand needs: at its
# datasheet speeds the RH5DG2's fingers close 1.32 rad in 0.66 s, its thumb yaws 1.18 rad in 0.79 s.
DURATIONS = {"approach": 60, "descend": 40, "close": 40, "close_late": 50, "hold": 10, "lift": 40,
             "carry": 60, "lower": 40, "open": 20, "retreat": 30}
APPROACH_HEIGHT_M = 0.12
NOT_IN_HAND_M = 0.06          # an object this far from where the hand holds it is not in the hand at all
SMOOTHSTEP_PEAK = 1.5         # a timeline segment's peak speed over its mean (SideTimeline.at)
LIFT_HEIGHT_M = 0.14


def pitched_palm_down(pitch_deg: float) -> np.ndarray:
    """PALM_DOWN with the fingers turned ``pitch_deg`` down about the world x axis."""
    a = np.radians(pitch_deg)
    about_x = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(a), np.sin(a)], [0.0, -np.sin(a), np.cos(a)]])
    return about_x @ PALM_DOWN


def yawed(R: np.ndarray, yaw: float) -> np.ndarray:
    """``R`` turned by ``yaw`` radians about the world z axis."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ R


def yaw_of(R: np.ndarray) -> float:
    """Turn (radians) of rotation ``R``'s x axis about the vertical, from world x."""
    return float(np.arctan2(R[1, 0], R[0, 0]))


def axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix of ``angle`` radians about the unit ``axis``."""
    q, R = np.zeros(4), np.zeros(9)
    mujoco.mju_axisAngle2Quat(q, np.asarray(axis, float), angle)
    mujoco.mju_quat2Mat(R, q)
    return R.reshape(3, 3)


def quat(R: np.ndarray) -> np.ndarray:
    """The quaternion (w, x, y, z) of rotation matrix ``R``."""
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, R.flatten())
    return q


def slerp(q0: np.ndarray, q1: np.ndarray, s: float) -> np.ndarray:
    if np.dot(q0, q1) < 0:
        q1 = -q1
    dot = min(1.0, float(np.dot(q0, q1)))
    theta = np.arccos(dot)
    if theta < 1e-6:
        return q1.copy()
    return (np.sin((1 - s) * theta) * q0 + np.sin(s * theta) * q1) / np.sin(theta)


@dataclass
class Keyframe:
    end_step: int
    pos: np.ndarray
    quat: np.ndarray
    hand: np.ndarray        # hand actuator targets (layout order)


class SideTimeline:
    """Piecewise-linear wrist path and hand actuator targets of one side."""

    def __init__(self, start_pos, start_quat, start_hand, start_step: int = 0):
        self.frames = [Keyframe(start_step, np.asarray(start_pos, float), np.asarray(start_quat, float),
                                np.asarray(start_hand, float))]

    @property
    def end(self) -> int:
        return self.frames[-1].end_step

    def add(self, duration: int, pos=None, quat=None, hand=None) -> None:
        last = self.frames[-1]
        self.frames.append(Keyframe(last.end_step + duration, last.pos if pos is None else np.asarray(pos, float),
                                    last.quat if quat is None else np.asarray(quat, float),
                                    last.hand if hand is None else np.asarray(hand, float)))

    def at(self, step: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        prev = self.frames[0]
        for frame in self.frames[1:]:
            if step < frame.end_step:
                s = (step - prev.end_step) / max(1, frame.end_step - prev.end_step)
                s = min(max(s, 0.0), 1.0)
                s = s * s * (3 - 2 * s)     # smoothstep: zero velocity at keyframes
                return (prev.pos + s * (frame.pos - prev.pos), slerp(prev.quat, frame.quat, s),
                        prev.hand + s * (frame.hand - prev.hand))
            prev = frame
        return prev.pos, prev.quat, prev.hand


def roll_then_swing(R0: np.ndarray, R1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """From wrist-site rotation ``R0`` to ``R1`` as a roll about ``R0``'s fingers (site z) and then the least
    swing of the fingers onto ``R1``'s: the rotations half way through the roll and at its end. A roll of
    half a turn has no shorter way round: it goes the way that has the palm (site y) facing up half way (rolled
    palm down, the RM65 lost its IK branch in faucet_cup_water_fill's lever pull, seed 0)."""
    z0, z1 = R0[:, 2], R1[:, 2]
    axis = np.cross(z0, z1)
    if np.linalg.norm(axis) < 1e-9:                 # fingers already along z1, or reversed: swing about the thumb side
        axis = R0[:, 0]
    swing = axis_rotation(axis / np.linalg.norm(axis), np.arccos(np.clip(z0 @ z1, -1.0, 1.0)))
    rolled = swing.T @ R1                           # R0 rolled about z0
    roll = float(np.arctan2(np.cross(R0[:, 0], rolled[:, 0]) @ z0, R0[:, 0] @ rolled[:, 0]))
    ways = (roll, roll - 2 * np.pi * np.sign(roll)) if abs(roll) > np.radians(170.0) else (roll,)
    roll = max(ways, key=lambda a: float((axis_rotation(z0, a / 2) @ R0)[2, 1]))
    return axis_rotation(z0, roll / 2) @ R0, rolled
