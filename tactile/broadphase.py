"""Broad phase: can a site's rays reach a target at all?

Each site's ray volume is bounded by a box in its attach-body frame: the box around its valid
surface points and the same points advanced ``max_range`` along their inward normals (the pad swept
along its normal). Each target is bounded by its local-frame AABB. Both become oriented boxes in
the world and meet a separating-axis test; a site-target pair is ray cast only if they overlap.
All pairs first meet a cheap world-AABB test in one numpy step, so that the exact test runs only
on the few pairs that are close (a scene may have 60 target geoms and 10 sites).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SEPARATION_EPS = 1e-9
AABB_MARGIN_M = 1e-6     # far above the separating-axis test's tolerance: never drops a pair it keeps


@dataclass(frozen=True)
class LocalBox:
    """Axis-aligned box in some local frame: centre and half extents (metres)."""

    center: np.ndarray
    half: np.ndarray

    @classmethod
    def around(cls, points: np.ndarray) -> "LocalBox":
        lo, hi = points.min(axis=0), points.max(axis=0)
        return cls((lo + hi) / 2, (hi - lo) / 2)

    def in_world(self, pos, rot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(centre, rotation, half extents) of this box placed by the pose (pos, rot)."""
        rot = np.asarray(rot, dtype=np.float64)
        return rot @ self.center + np.asarray(pos, dtype=np.float64), rot, self.half


def ray_volume_box(points_m: np.ndarray, normals: np.ndarray, max_range: float) -> LocalBox:
    """Box holding every ray segment p + t n, 0 <= t <= max_range (attach-body frame)."""
    return LocalBox.around(np.concatenate([points_m, points_m + max_range * normals]))


def world_aabbs(boxes) -> tuple[np.ndarray, np.ndarray]:
    """(lo [N, 3], hi [N, 3]) world axis-aligned bounds of oriented boxes (centre, rotation, half)."""
    centres = np.array([c for c, _, _ in boxes]).reshape(-1, 3)
    reach = np.array([np.abs(r) @ h for _, r, h in boxes]).reshape(-1, 3) + AABB_MARGIN_M
    return centres - reach, centres + reach


def aabb_overlaps(a, b) -> np.ndarray:
    """[Na, Nb] bool: which of a's world AABBs overlap which of b's (each given as (lo, hi))."""
    (lo_a, hi_a), (lo_b, hi_b) = a, b
    return np.all((lo_a[:, None] <= hi_b[None]) & (lo_b[None] <= hi_a[:, None]), axis=2)


def boxes_overlap(a, b) -> bool:
    """Separating-axis test of two oriented boxes given as (centre, rotation, half extents)."""
    ca, ra, ha = a
    cb, rb, hb = b
    r = ra.T @ rb  # b's axes in a's frame
    t = ra.T @ (cb - ca)
    abs_r = np.abs(r) + SEPARATION_EPS
    if np.any(np.abs(t) > ha + abs_r @ hb):  # a's face axes
        return False
    if np.any(np.abs(r.T @ t) > abs_r.T @ ha + hb):  # b's face axes
        return False
    for i in range(3):  # edge-edge axes a_i x b_j
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            reach = ha[i1] * abs_r[i2, j] + ha[i2] * abs_r[i1, j] + hb[j1] * abs_r[i, j2] + hb[j2] * abs_r[i, j1]
            if abs(t[i2] * r[i1, j] - t[i1] * r[i2, j]) > reach:
                return False
    return True
