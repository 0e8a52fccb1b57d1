"""Rigid frames for the robot descriptions: URDF roll-pitch-yaw, frames from axes, quaternions, transforms."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .fields import DescriptionError


def rpy_to_matrix(rpy) -> np.ndarray:
    """URDF fixed-axis roll-pitch-yaw: R = Rz(yaw) @ Ry(pitch) @ Rx(roll)."""
    r, p, y = (float(v) for v in rpy)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ])


def frame_from_axes(z, y) -> np.ndarray:
    """Rotation whose z column is ``z`` and whose y column is ``y`` orthogonalised against it."""
    z = np.asarray(z, float)
    z = z / np.linalg.norm(z)
    y = np.asarray(y, float)
    y = y - z * (y @ z)
    n = np.linalg.norm(y)
    if n < 1e-9:
        raise DescriptionError(f"frame axes z={z} and y={y} are parallel")
    y = y / n
    x = np.cross(y, z)
    return np.column_stack([x, y, z])


def mat_to_quat(R: np.ndarray) -> np.ndarray:
    """Rotation matrix -> unit quaternion (w, x, y, z), w >= 0."""
    import mujoco

    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=float).reshape(9))
    if q[0] < 0:
        q = -q
    return q


def quat_to_mat(q) -> np.ndarray:
    import mujoco

    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, np.asarray(q, float))
    return R.reshape(3, 3)


@dataclass(frozen=True)
class Transform:
    """Rigid transform (rotation matrix + translation) used for origins and mounts."""

    pos: np.ndarray
    rot: np.ndarray

    @staticmethod
    def identity() -> "Transform":
        return Transform(np.zeros(3), np.eye(3))

    def __matmul__(self, other: "Transform") -> "Transform":
        return Transform(self.pos + self.rot @ other.pos, self.rot @ other.rot)

    def inverse(self) -> "Transform":
        return Transform(-self.rot.T @ self.pos, self.rot.T)

    def to_local(self, points) -> np.ndarray:
        """Points (3,) or (n, 3) given in the parent frame, expressed in this frame."""
        return (np.asarray(points, float) - self.pos) @ self.rot

    @property
    def quat(self) -> np.ndarray:
        return mat_to_quat(self.rot)



def frame_transform(frame) -> Transform:
    """A validated `sim.schema.robot_parts.Frame` (or None: identity) as a Transform."""
    if frame is None:
        return Transform.identity()
    pos = np.asarray(frame.xyz if frame.xyz is not None else [0, 0, 0], dtype=float)
    if frame.rpy is not None:
        rot = rpy_to_matrix(frame.rpy)
    elif frame.z is not None:
        rot = frame_from_axes(frame.z, frame.y)
    elif frame.quat is not None:
        rot = quat_to_mat(np.asarray(frame.quat, dtype=float) / np.linalg.norm(frame.quat))
    else:
        rot = np.eye(3)
    return Transform(pos, rot)
