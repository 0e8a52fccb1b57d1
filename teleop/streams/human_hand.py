"""A parametric human hand: 21 MediaPipe keypoints in the wrist frame (see ``frame.py``) from finger
curls and a thumb-tip goal. It generates operator input where no person is at hand: the tests'
open hands and pinches, and the scripted operator's grasps.

Sizes are those of an adult hand about 0.19 m long (wrist crease to middle fingertip), with
phalanx lengths of hand length times approximately the segment proportions of Buchholz, Armstrong
and Goldstein (1992); the palm is flat (no metacarpal arch). Fingers flex about their own lateral axis (towards
+y, the palm side); the thumb is a smooth curve from its CMC joint to a tip goal, which is enough
for DexPilot, which reads only the fingertips and the wrist.
"""

from __future__ import annotations

import numpy as np

from sim.embodiment.mirror import M

from .frame import KP, NUM_KEYPOINTS, side_index

HAND_LENGTH_M = 0.19
FINGERS = ("index", "middle", "ring", "pinky")
# right hand, wrist frame (m): MCP joints, phalanx lengths (proximal, middle, distal to the tip)
# and the sideways fan of the open fingers (rad about +y; + spreads towards the little finger)
MCP = {"index": (-0.023, 0.0, 0.083), "middle": (0.0, 0.0, 0.085), "ring": (0.019, 0.0, 0.080),
       "pinky": (0.036, 0.0, 0.071)}
PHALANGES = {"index": (0.050, 0.027, 0.018), "middle": (0.053, 0.032, 0.021), "ring": (0.049, 0.031, 0.020),
             "pinky": (0.039, 0.022, 0.018)}
SPREAD = {"index": -0.12, "middle": 0.0, "ring": 0.10, "pinky": 0.22}
FULL_CURL = (1.45, 1.65, 1.10)          # MCP, PIP, DIP flexion at curl 1 (rad)
THUMB_CMC = np.array([-0.020, 0.012, 0.028])
THUMB_LENGTH = 0.115                    # CMC -> tip, straight
THUMB_OPEN_DIR = np.array([-0.62, 0.28, 0.73]) / np.linalg.norm([-0.62, 0.28, 0.73])
THUMB_OPPOSED_DIR = np.array([0.15, 0.75, 0.65]) / np.linalg.norm([0.15, 0.75, 0.65])
THUMB_JOINT_T = (0.42, 0.72)            # curve parameters of the MCP and IP keypoints
MIRROR = np.diag(M)                     # the left hand: the embodiment's left/right reflection


def _rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def finger_points(finger: str, curl: float) -> np.ndarray:
    """MCP, PIP, DIP and tip of one finger of the right hand (4, 3) at curl 0 (straight) .. 1 (fist)."""
    R = _rot_y(SPREAD[finger])
    p = np.asarray(MCP[finger], float)
    out = [p.copy()]
    for length, full in zip(PHALANGES[finger], FULL_CURL):
        R = R @ _rot_x(-full * curl)    # flexion about -x turns +z towards +y (the palm side)
        p = p + R @ np.array([0.0, 0.0, length])
        out.append(p.copy())
    return np.array(out)


def thumb_open_tip() -> np.ndarray:
    return THUMB_CMC + THUMB_LENGTH * THUMB_OPEN_DIR


def thumb_points(tip: np.ndarray, opposition: float) -> np.ndarray:
    """CMC, MCP, IP and tip of the right thumb: a quadratic curve from the CMC, leaving it along a
    metacarpal direction between open (0) and opposed (1), ending at ``tip``."""
    d = (1 - opposition) * THUMB_OPEN_DIR + opposition * THUMB_OPPOSED_DIR
    d = d / np.linalg.norm(d)
    ctrl = THUMB_CMC + 0.06 * d
    tip = np.asarray(tip, float)

    def curve(t):
        return (1 - t) ** 2 * THUMB_CMC + 2 * (1 - t) * t * ctrl + t * t * tip

    return np.array([THUMB_CMC, curve(THUMB_JOINT_T[0]), curve(THUMB_JOINT_T[1]), tip])


def hand_keypoints(curl=(0.0, 0.0, 0.0, 0.0), thumb_tip=None, opposition: float = 0.0,
                   side: str = "right") -> np.ndarray:
    """(21, 3) keypoints in the wrist frame: ``curl`` per finger (index, middle, ring, pinky), the
    thumb tip goal (default: the open thumb) and how far the thumb is opposed (0..1)."""
    if len(curl) != len(FINGERS):
        raise ValueError(f"curl: expected {len(FINGERS)} values (index, middle, ring, pinky), got {len(curl)}")
    kp = np.zeros((NUM_KEYPOINTS, 3))
    for finger, c in zip(FINGERS, curl):
        kp[KP[f"{finger}_mcp"]: KP[f"{finger}_tip"] + 1] = finger_points(finger, float(c))
    tip = thumb_open_tip() if thumb_tip is None else np.asarray(thumb_tip, float)
    kp[KP["thumb_cmc"]: KP["thumb_tip"] + 1] = thumb_points(tip, float(opposition))
    return kp * MIRROR if side_index(side) == 0 else kp


def open_hand(side: str = "right") -> np.ndarray:
    return hand_keypoints(side=side)


def pinch(finger: str = "index", curl: float = 0.5, gap_m: float = 0.012, side: str = "right") -> np.ndarray:
    """The thumb tip ``gap_m`` from one finger's tip (keypoints sit at the finger ends, so touching
    pads leave about a centimetre between them), that finger curled, the others slightly curled."""
    curls = [0.15] * len(FINGERS)
    curls[FINGERS.index(finger)] = curl
    target = finger_points(finger, curl)[-1]
    away = thumb_open_tip() - target
    tip = target + gap_m * away / np.linalg.norm(away)
    return hand_keypoints(curls, tip, opposition=0.8, side=side)


def power_grasp(closure: float, side: str = "right") -> np.ndarray:
    """Open (0) .. closed around a handle (1): fingers curl together and the thumb wraps over the
    index finger's middle phalanx."""
    c = float(np.clip(closure, 0.0, 1.0))
    curls = [0.85 * c] * len(FINGERS)
    index = finger_points("index", curls[0])
    wrap = 0.5 * (index[1] + index[2]) + np.array([-0.01, 0.02, 0.0])
    tip = (1 - c) * thumb_open_tip() + c * wrap
    return hand_keypoints(curls, tip, opposition=c, side=side)
