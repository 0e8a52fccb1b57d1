"""Small rigid-body helpers on (pos, wxyz quat, half extents) boxes."""

from __future__ import annotations

import math

import numpy as np

Z_UP = np.array([0.0, 0.0, 1.0])


def length(v) -> float:
    """Euclidean length of a small vector; ~4x cheaper than np.linalg.norm, which the evaluator
    calls dozens of times per step (recorder overhead, `b2d bench recorder`). Kept on np.dot (BLAS):
    a Python sum of squares rounds differently in ~10% of cases, and recorded results must not move."""
    if type(v) is not np.ndarray or v.dtype != np.float64:
        v = np.asarray(v, dtype=float)
    return math.sqrt(v.dot(v))


# The evaluator asks for one object's rotation several times per update (each predicate on it, the
# monitors): a small cache keyed by the quaternion's bytes computes it once per object and update.
# The matrices are read-only, so a caller cannot change a cached one.
_ROTATIONS: dict[bytes, np.ndarray] = {}
_ROTATIONS_MAX = 256


def rotation(quat: np.ndarray) -> np.ndarray:
    """3x3 rotation matrix of a wxyz quaternion (normalised first), read-only."""
    q = np.asarray(quat, dtype=float)
    key = q.tobytes() if q.shape == (4,) else None
    rot = _ROTATIONS.get(key) if key is not None else None
    if rot is None:
        rot = _rotation(q)
        rot.flags.writeable = False
        if key is not None:
            if len(_ROTATIONS) >= _ROTATIONS_MAX:
                _ROTATIONS.clear()
            _ROTATIONS[key] = rot
    return rot


def _rotation(q: np.ndarray) -> np.ndarray:
    # Python floats (tolist) instead of numpy scalars: the same IEEE arithmetic, ~3x less overhead
    w, x, y, z = (q / length(q)).tolist()
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    """Angle between two vectors in degrees."""
    c = float(np.dot(a, b) / (length(a) * length(b)))
    # clamped by hand: np.clip on a scalar goes through a slow Python wrapper (NaN stays NaN, as there)
    c = 1.0 if c > 1.0 else -1.0 if c < -1.0 else c
    return float(np.degrees(np.arccos(c)))


def tilt_deg(quat: np.ndarray, local_axis: np.ndarray) -> float:
    """Angle between an object's local axis (in world) and world +z."""
    return angle_deg(rotation(quat) @ local_axis, Z_UP)


def vertical_half_extent(quat: np.ndarray, half_extents: np.ndarray) -> float:
    """Half height of a rotated box: its world z extent around the centre."""
    return float(np.abs(rotation(quat)[2]) @ np.asarray(half_extents, dtype=float))


def to_local(point: np.ndarray, pos: np.ndarray, quat: np.ndarray) -> np.ndarray:
    """A world point in a body's frame."""
    return rotation(quat).T @ (np.asarray(point, dtype=float) - pos)


def box_distance(point: np.ndarray, pos: np.ndarray, quat: np.ndarray, half_extents: np.ndarray) -> float:
    """Distance from a world point to an oriented box (0 inside)."""
    local = to_local(point, pos, quat)
    return float(length(local - np.clip(local, -half_extents, half_extents)))


def axis_extent(local_axis: np.ndarray, half_extents: np.ndarray) -> float:
    """How far the box surface lies from the centre along a unit local axis (box support value)."""
    return float(np.abs(local_axis) @ half_extents)


_AXES = {"xy": slice(0, 2), "xyz": slice(0, 3), "z": slice(2, 3)}


def masked_distance(a: np.ndarray, b: np.ndarray, axes: str) -> float:
    """Distance between two points over 'xy', 'xyz' or 'z'."""
    sel = _AXES[axes]
    return float(length(np.asarray(a, dtype=float)[sel] - np.asarray(b, dtype=float)[sel]))
