"""2D boxes per camera and object, from the instance mask, with a cheap visibility fraction.

Box (`xyxy`, float32 pixels): the box of the object's visible pixels in the instance mask, in
pixel-edge coordinates, the frame of the stored intrinsics (cx = W/2): pixel (u, v) covers
[u, u+1) x [v, v+1), so x1, y1 are inclusive (the first column / row showing the object) and x2, y2
exclusive (last column / row + 1). The box is modal: it covers what the camera sees, clipped to the
image. An object with no visible pixel has xyxy = NaN and visibility 0.

Visibility (float32 in [0, 1]): the fraction of the object's surface that the camera sees, taken
from a fixed set of area-uniform surface samples (`SAMPLES_PER_OBJECT`, seeded, in each geom's
frame). A sample counts as seen when it lies in front of the camera, projects into the image, and the
instance mask shows the object at its pixel or a 4-neighbour (one pixel of rasterisation slack).
Samples on the far side of the object project inside its own silhouette, so an unoccluded object
inside the image scores about 1; occluders and the image border lower it. It needs no second
render and costs one projection of the samples per camera.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
import trimesh

from sim.labels.geometry import GeomShapes, check_solid
from sim.labels.ids import LabelIds
from sim.render import MJ_TO_CV, intrinsic_matrix

SAMPLES_PER_OBJECT = 256
SAMPLE_SEED = 0


@dataclass(frozen=True)
class Boxes2D:
    xyxy: np.ndarray          # [N, 4] float32, NaN rows for objects not visible
    visibility: np.ndarray    # [N] float32
    pixels: np.ndarray        # [N] int64 visible pixel count


def mask_boxes(instance: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """xyxy [count, 4] (NaN when absent) and pixel counts [count] of instances 1..count.

    Objects cover a few percent of an image: one pass finds the object pixels (on a boolean mask,
    whose nonzero search is several times faster than a uint16 one), and only those are visited.
    Counts of (instance, row) and (instance, column) pairs give each instance's occupied rows and
    columns."""
    xyxy = np.full((count, 4), np.nan, np.float32)
    height, width = instance.shape
    flat = instance.ravel()
    where = np.flatnonzero(flat != 0)
    if not where.size:
        return xyxy, np.zeros(count, np.int64)
    labels = flat[where].astype(np.intp)
    if labels.max() > count:
        raise ValueError(f"instance mask: id {int(labels.max())} above the {count} objects")
    rows = where // width
    cols = where - rows * width
    in_row = np.bincount(labels * height + rows, minlength=(count + 1) * height).reshape(count + 1, height)[1:] > 0
    in_col = np.bincount(labels * width + cols, minlength=(count + 1) * width).reshape(count + 1, width)[1:] > 0
    pixels = np.bincount(labels, minlength=count + 1)[1:]
    seen = pixels > 0
    # first occupied column / row, and last + 1 (argmax finds the first True)
    xyxy[seen, 0] = in_col[seen].argmax(axis=1)
    xyxy[seen, 1] = in_row[seen].argmax(axis=1)
    xyxy[seen, 2] = width - in_col[seen, ::-1].argmax(axis=1)
    xyxy[seen, 3] = height - in_row[seen, ::-1].argmax(axis=1)
    return xyxy, pixels.astype(np.int64)


def camera_projection(model: mujoco.MjModel, data: mujoco.MjData, camera: int, width: int, height: int):
    """Intrinsics K [3, 3] and camera-from-world (R [3, 3], t [3]) in the OpenCV camera frame."""
    K = intrinsic_matrix(float(model.cam_fovy[camera]), width, height)
    world_from_cam = data.cam_xmat[camera].reshape(3, 3) @ MJ_TO_CV
    return K, world_from_cam.T, -world_from_cam.T @ data.cam_xpos[camera]


class SurfaceSamples:
    """Area-uniform surface points of every object, each held in the frame of the geom it lies on."""

    def __init__(self, model: mujoco.MjModel, ids: LabelIds, shapes: GeomShapes | None = None,
                 per_object: int = SAMPLES_PER_OBJECT, seed: int = SAMPLE_SEED):
        shapes = shapes or GeomShapes(model)
        geoms, points, owner = [], [], []
        for inst in range(1, len(ids.instance_names)):
            mine = ids.instance_geoms(inst)
            if not len(mine):
                raise ValueError(f"object '{ids.instance_names[inst]}' has no geoms to sample")
            check_solid(model, mine)
            meshes = [shapes.surface(int(g)) for g in mine]
            face_geom = np.repeat(mine, [len(m.faces) for m in meshes])
            pts, faces = trimesh.sample.sample_surface(trimesh.util.concatenate(meshes), per_object, seed=seed)
            geoms.append(face_geom[faces])
            points.append(pts)
            owner.append(np.full(per_object, inst))
        self.geom = np.concatenate(geoms) if geoms else np.zeros(0, int)
        self.local = np.concatenate(points) if points else np.zeros((0, 3))
        self.instance = np.concatenate(owner) if owner else np.zeros(0, int)
        self.count = len(ids.instance_names) - 1
        self.per_object = per_object
        self._geoms = np.unique(self.geom)
        self._last = None       # (geom poses, points) of the last world() call

    def world(self, data: mujoco.MjData) -> np.ndarray:
        """[N, 3] world points (read-only). Every camera of a frame asks for the same points: they are
        recomputed only when the sampled geoms' poses changed (compared bit for bit)."""
        pose = np.concatenate([data.geom_xpos[self._geoms].ravel(), data.geom_xmat[self._geoms].ravel()])
        last = self._last
        if last is not None and np.array_equal(pose.view(np.int64), last[0].view(np.int64)):
            return last[1]
        rot = data.geom_xmat[self.geom].reshape(-1, 3, 3)
        points = data.geom_xpos[self.geom] + np.einsum("nij,nj->ni", rot, self.local)
        points.flags.writeable = False
        self._last = pose, points
        return points


class Box2DLabeler:
    """``capture(data, camera, instance_mask)`` -> `Boxes2D` of every object for that camera."""

    def __init__(self, model: mujoco.MjModel, ids: LabelIds, shapes: GeomShapes | None = None,
                 per_object: int = SAMPLES_PER_OBJECT):
        self.model = model
        self.ids = ids
        self.samples = SurfaceSamples(model, ids, shapes, per_object)

    def capture(self, data: mujoco.MjData, camera: int | str, instance: np.ndarray) -> Boxes2D:
        cam = camera if isinstance(camera, (int, np.integer)) else self.model.camera(camera).id
        height, width = instance.shape
        n = self.samples.count
        xyxy, pixels = mask_boxes(instance, n)
        K, R, t = camera_projection(self.model, data, int(cam), width, height)
        pc = self.samples.world(data) @ R.T + t
        z = pc[:, 2]
        ahead = z > 1e-9
        safe_z = np.where(ahead, z, 1.0)
        u = np.floor(K[0, 0] * pc[:, 0] / safe_z + K[0, 2]).astype(np.int64)
        v = np.floor(K[1, 1] * pc[:, 1] / safe_z + K[1, 2]).astype(np.int64)
        inside = np.flatnonzero(ahead & (u >= 0) & (u < width) & (v >= 0) & (v < height))
        u, v, inst = u[inside], v[inside], self.samples.instance[inside]
        # the sample's pixel and its 4 neighbours as flat indices; past the border a neighbour is the
        # pixel itself (as clipping it to the image would give)
        flat = instance.ravel()
        pixel = v * width + u
        seen = flat[pixel] == inst
        seen |= flat[pixel + (u < width - 1)] == inst
        seen |= flat[pixel - (u > 0)] == inst
        seen |= flat[pixel + width * (v < height - 1)] == inst
        seen |= flat[pixel - width * (v > 0)] == inst
        fraction = np.bincount(inst[seen], minlength=n + 1)[1:] / float(self.samples.per_object)
        return Boxes2D(xyxy, fraction.astype(np.float32), pixels)
