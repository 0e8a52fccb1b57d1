"""The operator stream: what every input device is turned into, one frame at a time.

Per frame: a timestamp (ns) and, per hand (index 0 = left, 1 = right, as ``SIDES``):

* ``keypoints`` (21, 3): the 21 MediaPipe hand keypoints in metres, in the hand's WRIST FRAME:
  origin at the wrist keypoint, +z towards the middle-finger MCP, +y the palm normal (the side the
  fingers curl towards), +x = y x z. For a right hand the thumb lies on -x, for a left hand on +x.
  This is the robot hand-base convention of ``sim/embodiment/description.py``, so retargeting
  compares like with like and the left hand is the mirror image of the right.
* ``wrist_pos`` (3,) and ``wrist_quat`` (4, w x y z): the pose of that wrist frame in the tracker's
  world frame (any fixed right-handed metric frame: the arm follows wrist motion relative to an
  anchor taken at reset, so the tracker's world frame needs no calibration).
* ``keypoints_valid`` / ``wrist_valid`` (bool): the device tracked that part in this frame.

Devices that provide only one part (a glove: keypoints; ARKit: wrists) mark the other invalid;
``CombinedStream`` merges two such sources. Values of invalid parts are not read.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from sim.embodiment.retarget_spec import MEDIAPIPE_KEYPOINTS

SIDES = ("left", "right")
NUM_KEYPOINTS = len(MEDIAPIPE_KEYPOINTS)
KP = {name: i for i, name in enumerate(MEDIAPIPE_KEYPOINTS)}
IDENTITY_QUAT = np.array([1.0, 0.0, 0.0, 0.0])


def side_index(side: str) -> int:
    if side not in SIDES:
        raise ValueError(f"unknown side {side!r}; valid: {list(SIDES)}")
    return SIDES.index(side)


@dataclass(frozen=True)
class OperatorFrame:
    timestamp_ns: int
    keypoints: np.ndarray        # (2, 21, 3) float64, wrist frame
    wrist_pos: np.ndarray        # (2, 3) float64, tracker frame
    wrist_quat: np.ndarray       # (2, 4) float64, w x y z
    keypoints_valid: np.ndarray  # (2,) bool
    wrist_valid: np.ndarray      # (2,) bool

    def __post_init__(self):
        shapes = {"keypoints": (2, NUM_KEYPOINTS, 3), "wrist_pos": (2, 3), "wrist_quat": (2, 4),
                  "keypoints_valid": (2,), "wrist_valid": (2,)}
        for name, shape in shapes.items():
            value = np.asarray(getattr(self, name))
            if value.shape != shape:
                raise ValueError(f"OperatorFrame field '{name}': expected shape {shape}, got {value.shape}")

    @staticmethod
    def empty(timestamp_ns: int) -> "OperatorFrame":
        """A frame with nothing tracked (parts are filled in by the adapters)."""
        return OperatorFrame(int(timestamp_ns), np.zeros((2, NUM_KEYPOINTS, 3)), np.zeros((2, 3)),
                             np.tile(IDENTITY_QUAT, (2, 1)), np.zeros(2, bool), np.zeros(2, bool))

    def with_hand(self, side: str, keypoints=None, wrist_pos=None, wrist_quat=None) -> "OperatorFrame":
        """A copy with one hand's keypoints and/or wrist pose set (and marked valid)."""
        i = side_index(side)
        kp, wp, wq = self.keypoints.copy(), self.wrist_pos.copy(), self.wrist_quat.copy()
        kv, wv = self.keypoints_valid.copy(), self.wrist_valid.copy()
        if keypoints is not None:
            kp[i], kv[i] = np.asarray(keypoints, float), True
        if wrist_pos is not None or wrist_quat is not None:
            if wrist_pos is None or wrist_quat is None:
                raise ValueError("a wrist pose needs both wrist_pos and wrist_quat")
            wp[i], wq[i], wv[i] = np.asarray(wrist_pos, float), np.asarray(wrist_quat, float), True
        return OperatorFrame(self.timestamp_ns, kp, wp, wq, kv, wv)


class OperatorStream(Protocol):
    """A live or recorded source: ``poll()`` returns the newest frame not yet returned, or None when
    nothing new has arrived (the sanitizer counts that step as a dropped frame)."""

    def poll(self) -> OperatorFrame | None: ...


def wrist_frame_from_keypoints(points: np.ndarray, side: str) -> tuple[np.ndarray, np.ndarray]:
    """Rotation (3x3, columns = wrist-frame axes) and origin of the wrist frame of 21 keypoints given
    in any right-handed frame: z from the wrist to the middle MCP, x across the knuckles (index to
    pinky for a right hand, pinky to index for a left one), y = z x x."""
    p = np.asarray(points, float)
    z = p[KP["middle_mcp"]] - p[KP["wrist"]]
    across = p[KP["pinky_mcp"]] - p[KP["index_mcp"]]
    if side_index(side) == 0:
        across = -across
    nz = np.linalg.norm(z)
    if not nz > 1e-6:
        raise ValueError("keypoints: wrist and middle_mcp coincide; no wrist frame")
    z = z / nz
    y = np.cross(z, across)
    ny = np.linalg.norm(y)
    if not ny > 1e-6:
        raise ValueError("keypoints: the knuckle line is parallel to the wrist-middle line; no wrist frame")
    y = y / ny
    x = np.cross(y, z)
    return np.column_stack([x, y, z]), p[KP["wrist"]].copy()


def to_wrist_frame(points: np.ndarray, side: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Keypoints given in a tracker frame -> (keypoints in the wrist frame, wrist rotation, wrist origin)."""
    R, origin = wrist_frame_from_keypoints(points, side)
    return (np.asarray(points, float) - origin) @ R, R, origin
