"""Occupancy grid of the workspace, method "mesh": a voxel is occupied when its centre lies inside
(or on) a labelled geom, tested analytically for primitives and by containment for meshes.

Grid layout: `sim.labels.grid` (world-frame bounds; voxel [i, j, k] centred at
bounds[0] + (i + 0.5, j + 0.5, k + 0.5) * voxel). Each voxel holds a semantic id (uint8,
`LabelIds.semantic_names`, 0 = free) and an instance id (uint16, 0 = no object). Where geoms
overlap (contacts, compound parts) the higher semantic id wins, then the higher instance id, so
objects win over the robot and the table (robot parts among themselves follow `LabelIds.from_scene`'s
class order: base, left arm, left hand, right arm, right hand). Only labelled geoms fill voxels
(objects, robot, table); planes are infinite half-spaces and are left out, like everything of the
world body (floor).

Speed: per frame, each geom's world bounds select the block of voxel centres it can contain; the
block's local coordinates are outer sums of three axis vectors and its result is merged into the grid
in place (no per-voxel index arrays). Geoms welded to the world (the table, the
robot torso, fixed object bases) are filled once from the model and copied per frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from sim.labels.geometry import PLANE, GeomShapes, check_solid
from sim.labels.grid import grid_shape
from sim.labels.ids import LabelIds

METHOD = "mesh"


@dataclass(frozen=True)
class Occupancy:
    semantic: np.ndarray    # [X, Y, Z] uint8
    instance: np.ndarray    # [X, Y, Z] uint16


class OccupancyLabeler:
    """``capture(data)`` -> `Occupancy` of the posed scene."""

    def __init__(self, model: mujoco.MjModel, ids: LabelIds, bounds, voxel_size: float,
                 shapes: GeomShapes | None = None):
        self.bounds = np.asarray(bounds, float)
        self.voxel_size = float(voxel_size)
        self.shape = grid_shape(self.bounds, self.voxel_size)
        self.shapes = shapes or GeomShapes(model)
        labelled = np.flatnonzero((ids.geom_semantic > 0) & (model.geom_type != PLANE))
        check_solid(model, labelled)
        # one key per geom: semantic id above instance id, so the maximum picks the winner
        self.key = (ids.geom_semantic.astype(np.uint32) << 16) | ids.geom_instance.astype(np.uint32)
        body = model.geom_bodyid[labelled]
        welded = (model.body_weldid[body] == 0) & (model.body_mocapid[body] < 0)   # mocap bodies move
        self.dynamic = labelled[~welded]
        rest = mujoco.MjData(model)
        mujoco.mj_kinematics(model, rest)     # world-welded geoms sit where the model puts them
        self._static = np.zeros(self.shape, np.uint32)
        self._fill(self._static, labelled[welded], rest)

    def capture(self, data: mujoco.MjData) -> Occupancy:
        keys = self._static.copy()
        self._fill(keys, self.dynamic, data)
        return Occupancy((keys >> 16).astype(np.uint8), (keys & 0xFFFF).astype(np.uint16))

    def _fill(self, keys: np.ndarray, geoms: np.ndarray, data: mujoco.MjData) -> None:
        if not len(geoms):
            return
        rot = data.geom_xmat[geoms].reshape(-1, 3, 3)
        pos = data.geom_xpos[geoms]
        lo, hi = self.shapes.bounds(geoms, rot, pos)
        origin, v, shape = self.bounds[0], self.voxel_size, np.array(self.shape)
        # voxels whose centre lies within the geom's bounds: first index with centre >= lo, last + 1
        first = np.clip(np.ceil((lo - origin) / v - 0.5), 0, shape).astype(np.int64)
        stop = np.clip(np.floor((hi - origin) / v - 0.5) + 1, 0, shape).astype(np.int64)
        for k in np.flatnonzero(np.all(stop > first, axis=1)):
            (i0, j0, k0), (i1, j1, k1) = first[k], stop[k]
            # the block's centres relative to the geom, along each world axis, then in its local frame
            # by broadcasting: local = R^T (p - x), one outer sum per local axis
            dx = origin[0] + (np.arange(i0, i1) + 0.5) * v - pos[k, 0]
            dy = origin[1] + (np.arange(j0, j1) + 0.5) * v - pos[k, 1]
            dz = origin[2] + (np.arange(k0, k1) + 0.5) * v - pos[k, 2]
            R = rot[k]
            x, y, z = (R[0, a] * dx[:, None, None] + R[1, a] * dy[None, :, None] + R[2, a] * dz[None, None, :]
                       for a in range(3))
            inside = self.shapes.contains(int(geoms[k]), x, y, z)
            block = keys[i0:i1, j0:j1, k0:k1]
            np.maximum(block, np.where(inside, self.key[geoms[k]], 0).astype(np.uint32), out=block)
