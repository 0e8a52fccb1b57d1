"""A pinch at a `grasp_point`: the pads close on the part of the object there (a bowl's rim, a mug's
handle) rather than on the whole object, as a person lifts a bowl by its rim between thumb and finger.

The width the pads must clear is the part's thickness along the pinch axis at that point: rays from
either side of it, a little way out, towards it, against the object's geoms (and its links')."""

from __future__ import annotations

import mujoco
import numpy as np

from teleop.geom_rays import nearest_hit
from teleop.transit import object_geoms

RAY_START_M = 0.03     # rays start this far either side of the grasp point: past a rim's thickness, inside a bowl


def part_width(model: mujoco.MjModel, data: mujoco.MjData, body: int, point: np.ndarray, axis: np.ndarray) -> float:
    """The thickness (metres) of object ``body`` through ``point`` (world) along ``axis``: between the
    first surfaces rays from RAY_START_M either side meet; 0 where they meet nothing."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    ends = []
    for sign in (1.0, -1.0):
        origin = point + sign * RAY_START_M * axis
        hit = nearest_hit(model, data, object_geoms(model, body), origin, -sign * axis)
        ends.append(RAY_START_M - hit if hit is not None else 0.0)
    return max(0.0, ends[0] + ends[1])
