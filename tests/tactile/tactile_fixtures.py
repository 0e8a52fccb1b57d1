"""Constants and helpers shared by the tactile tests (a uniquely named module, unlike conftest)."""

from pathlib import Path

import numpy as np

SHARPA_DIR = Path("/work/shared/models/sharpa_tacmap")
FLAT_PAD = dict(center=[0, 0, 0], normal=[0, 0, 1], axis=[0, 1, 0], length=0.02, width=0.02, curvature_radius=0)
ROUND_PAD = dict(
    center=[0, 0.008, 0.02], normal=[0, 1, 0], axis=[0, 0, 1], length=0.03, width=0.018, curvature_radius=0.009
)
IDENTITY = (np.zeros(3), np.eye(3))


def rotation(axis, angle):
    """Rotation matrix about ``axis`` by ``angle`` radians (Rodrigues)."""
    axis = np.asarray(axis, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k
