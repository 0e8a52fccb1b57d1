"""Oriented 3D boxes per object: the tight box of its geoms in the frame of its root body.

Per frame, each geom of an object (its base and its articulated links) is put in the root body's
frame and bounded exactly (boxes by their corners, spheres, ellipsoids, cylinders and capsules
analytically, meshes by their hull vertices); the union is the box. So an opening door grows its
fridge's box while the box keeps the fridge's orientation. Stored per object:

    center_world [3]  box centre in the world (m)
    size_lwh     [3]  full lengths along the body's x (l), y (w) and z (h) axes (m)
    quat_world   [4]  world orientation of the box = the root body's (w, x, y, z), w >= 0
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from sim.labels.geometry import GeomShapes, check_solid
from sim.labels.ids import LabelIds


@dataclass(frozen=True)
class Boxes3D:
    center_world: np.ndarray    # [N, 3]
    size_lwh: np.ndarray        # [N, 3]
    quat_world: np.ndarray      # [N, 4] wxyz, w >= 0


class Box3DLabeler:
    """``capture(data)`` -> `Boxes3D` of every object of `ids`, in instance order."""

    def __init__(self, model: mujoco.MjModel, ids: LabelIds, shapes: GeomShapes | None = None):
        self.shapes = shapes or GeomShapes(model)
        order = [ids.instance_geoms(i) for i in range(1, len(ids.instance_names))]
        for inst, geoms in enumerate(order, start=1):
            if not len(geoms):
                raise ValueError(f"object '{ids.instance_names[inst]}' has no geoms to bound")
            check_solid(model, geoms)
        self.geoms = np.concatenate(order) if order else np.zeros(0, int)
        self.starts = np.cumsum([0] + [len(g) for g in order[:-1]]).astype(int)
        self.bodies = ids.instance_body[1:]
        self.owner_body = np.repeat(self.bodies, [len(g) for g in order])

    def capture(self, data: mujoco.MjData) -> Boxes3D:
        n = len(self.bodies)
        if not n:
            return Boxes3D(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 4)))
        body_rot = data.xmat[self.owner_body].reshape(-1, 3, 3)
        body_pos = data.xpos[self.owner_body]
        geom_rot = data.geom_xmat[self.geoms].reshape(-1, 3, 3)
        rel_rot = np.einsum("gji,gjk->gik", body_rot, geom_rot)                 # R_body^T R_geom
        rel_pos = np.einsum("gji,gj->gi", body_rot, data.geom_xpos[self.geoms] - body_pos)
        lo, hi = self.shapes.bounds(self.geoms, rel_rot, rel_pos)
        lo, hi = np.minimum.reduceat(lo, self.starts), np.maximum.reduceat(hi, self.starts)
        rot = data.xmat[self.bodies].reshape(-1, 3, 3)
        centre = data.xpos[self.bodies] + np.einsum("nij,nj->ni", rot, (lo + hi) / 2)
        quat = data.xquat[self.bodies].copy()
        quat[quat[:, 0] < 0] *= -1.0
        return Boxes3D(centre, hi - lo, quat)
