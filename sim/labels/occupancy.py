"""Occupancy grid of the workspace, method "mesh": a voxel is occupied when its centre lies inside
(or on) a labelled geom, tested analytically for primitives and by containment for meshes.

Grid layout: `sim.labels.grid` (world-frame bounds; voxel [i, j, k] centred at
bounds[0] + (i + 0.5, j + 0.5, k + 0.5) * voxel). Each voxel holds a semantic id (uint8,
`LabelIds.semantic_names`, 0 = free) and an instance id (uint16, 0 = no object). Where geoms
overlap (contacts, compound parts) the higher semantic id wins, then the higher instance id, so
objects win over the robot and the table (robot parts among themselves follow `LabelIds.from_scene`'s
class order: base, left arm, left hand, right arm, right hand). Only labelled geoms fill voxels
(objects, robot, table); planes are infinite half-spaces and are left out, like everything of the
world body (floor). An object none of whose voxel centres lies inside it (thinner than a voxel: a
spoon's 1 cm round handle can fall between the centres of a 1 cm grid) occupies the voxel holding each
of its geoms' centres instead, so no object within the bounds is missing from the grid.

Speed: the geoms welded to the world (the table, the robot torso, fixed object bases) are filled
once from the model; their semantic and instance grids are copied per frame. Per frame, each moving
geom's world bounds select the block of voxel centres it can contain; the blocks of all moving geoms
are tested in one batch (one vectorised containment test per primitive type, one per mesh geom), and
only the voxels found inside are merged with the static keys and written to the copies.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from sim.labels.geometry import MESH, PLANE, GeomShapes, check_solid, primitive_contains
from sim.labels.grid import grid_shape
from sim.labels.ids import LabelIds

METHOD = "mesh"


@dataclass(frozen=True)
class Occupancy:
    semantic: np.ndarray    # [X, Y, Z] uint8
    instance: np.ndarray    # [X, Y, Z] uint16


class OccupancyLabeler:
    """``capture(data)`` -> `Occupancy` of the posed scene. Holds per-frame scratch memory: use one
    labeler per thread."""

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
        self._static = np.zeros(int(np.prod(self.shape)), np.uint32)      # flat keys
        for g in labelled[welded]:            # one geom at a time: a block's arrays at most in memory
            np.maximum.at(self._static, *self._inside(np.array([g]), rest))
        objects = labelled[ids.geom_instance[labelled] > 0]        # geoms of objects (those with instance ids)
        moving = np.isin(objects, self.dynamic)
        self._moving_objects = objects[moving]
        self._in_static = np.zeros(int(ids.geom_instance.max(initial=0)) + 1, bool)   # [instance] has a static voxel
        self._in_static[self._static & 0xFFFF] = True
        voxels, keys = self._thin_objects(objects[~moving], np.zeros(0, np.int64), np.zeros(0, np.uint32), rest)
        np.maximum.at(self._static, voxels, keys)
        self._in_static[keys & 0xFFFF] = True
        self._in_static[0] = False      # instance 0: no object
        self._semantic, self._instance = _split(self._static)
        self._merged = np.zeros_like(self._static)    # scratch, all zero between captures

    def capture(self, data: mujoco.MjData) -> Occupancy:
        semantic, instance = self._semantic.copy(), self._instance.copy()
        voxels, keys = self._inside(self.dynamic, data)
        voxels, keys = self._thin_objects(self._moving_objects, voxels, keys, data)
        if voxels.size:
            merged = self._merged
            try:                # the maximum over the geoms covering each voxel, then over the static key
                np.maximum.at(merged, voxels, keys)
                keys = np.maximum(merged[voxels], self._static[voxels])
            finally:
                merged[voxels] = 0
            semantic[voxels], instance[voxels] = _split(keys)
        return Occupancy(semantic.reshape(self.shape), instance.reshape(self.shape))

    def _inside(self, geoms: np.ndarray, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """Flat indices of the voxels whose centre lies inside one of `geoms` (posed as in `data`),
        with that geom's key; a voxel inside several geoms appears once per geom."""
        none = np.zeros(0, np.int64), np.zeros(0, np.uint32)
        if not len(geoms):
            return none
        rot = data.geom_xmat[geoms].reshape(-1, 3, 3)
        pos = data.geom_xpos[geoms]
        lo, hi = self.shapes.bounds(geoms, rot, pos)
        origin, v, shape = self.bounds[0], self.voxel_size, np.array(self.shape)
        # voxels whose centre lies within the geom's bounds: first index with centre >= lo, last + 1
        first = np.clip(np.ceil((lo - origin) / v - 0.5), 0, shape).astype(np.int64)
        stop = np.clip(np.floor((hi - origin) / v - 0.5) + 1, 0, shape).astype(np.int64)
        extent = np.maximum(stop - first, 0)
        # the non-empty blocks, grouped by geom type: each primitive type is one run of points
        kind = self.shapes.type[geoms]
        blocks = np.flatnonzero(extent.prod(axis=1))
        if not len(blocks):
            return none
        blocks = blocks[np.argsort(kind[blocks], kind="stable")]
        geoms, kind, rot, pos, first, extent = (a[blocks] for a in (geoms, kind, rot, pos, first, extent))
        # all blocks' voxels as 1-D arrays, in C order within each block (as a block array would be):
        # first the rows (i, j) of every block, then the voxels k of every row
        count = extent.prod(axis=1)
        rows = extent[:, 0] * extent[:, 1]
        row_owner = np.repeat(np.arange(len(blocks)), rows)
        place = np.arange(rows.sum()) - np.repeat(np.cumsum(rows) - rows, rows)
        i = place // extent[row_owner, 1] + first[row_owner, 0]
        j = place % extent[row_owner, 1] + first[row_owner, 1]
        depth = extent[row_owner, 2]
        k = np.arange(count.sum()) - np.repeat(np.cumsum(depth) - depth, depth)
        voxels = np.repeat((i * self.shape[1] + j) * self.shape[2] + first[row_owner, 2], depth) + k
        k += np.repeat(first[:, 2], count)
        # centres relative to the geom, then in its local frame: local_a = R[0, a] dx + R[1, a] dy +
        # R[2, a] dz, always summed left to right (a voxel gets the same floats in any batch); the
        # first two terms are per row
        dx = origin[0] + (i + 0.5) * v - pos[row_owner, 0]
        dy = origin[1] + (j + 0.5) * v - pos[row_owner, 1]
        dz = origin[2] + (k + 0.5) * v - np.repeat(pos[:, 2], count)
        row_rot = rot[row_owner]
        x, y, z = (np.repeat(row_rot[:, 0, a] * dx + row_rot[:, 1, a] * dy, depth)
                   + np.repeat(rot[:, 2, a], count) * dz for a in range(3))
        inside = np.empty(len(voxels), bool)
        ends = np.cumsum(count)
        starts = ends - count
        for t in np.unique(kind):
            members = np.flatnonzero(kind == t)
            if t == MESH:       # one hull (or mesh) per geom
                for b in members:
                    run = slice(starts[b], ends[b])
                    inside[run] = self.shapes.contains(int(geoms[b]), x[run], y[run], z[run])
            else:               # consecutive blocks: one test, with a size column per point
                run = slice(starts[members[0]], ends[members[-1]])
                size = np.repeat(self.shapes.size[geoms[members]].T, count[members], axis=1)
                inside[run] = primitive_contains(int(t), size, x[run], y[run], z[run])
        return voxels[inside], np.repeat(self.key[geoms], count)[inside]

    def _thin_objects(self, geoms: np.ndarray, voxels: np.ndarray, keys: np.ndarray,
                      data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """`voxels` and `keys` (of `_inside`) with, for each object among `geoms` that holds no voxel in
        them nor in the static grid, the voxel holding each of its geoms' centres (within the bounds)."""
        if not len(geoms):
            return voxels, keys
        present = self._in_static.copy()
        present[keys & 0xFFFF] = True
        missing = geoms[~present[self.key[geoms] & 0xFFFF]]
        if not len(missing):
            return voxels, keys
        cell = np.floor((data.geom_xpos[missing] - self.bounds[0]) / self.voxel_size).astype(np.int64)
        within = np.all((cell >= 0) & (cell < np.array(self.shape)), axis=1)
        extra = np.ravel_multi_index(cell[within].T, self.shape).astype(np.int64)
        return np.concatenate([voxels, extra]), np.concatenate([keys, self.key[missing[within]]])


def _split(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Semantic (uint8) and instance (uint16) ids of keys."""
    return (keys >> 16).astype(np.uint8), (keys & 0xFFFF).astype(np.uint16)
