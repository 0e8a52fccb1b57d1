"""The labels' fast paths against plain reference computations on small synthetic cases: the batched
occupancy fill, mask_boxes, the visibility's neighbour lookup and the per-pose sample cache."""

import mujoco
import numpy as np
import pytest
import trimesh

from label_scenes import HEIGHT, WIDTH, add_free_body, box, cube_scene, new_spec, place, render_seg
from sim.labels.box2d import Box2DLabeler, camera_projection, mask_boxes
from sim.labels.geometry import PLANE
from sim.labels.ids import LabelIds
from sim.labels.occupancy import OccupancyLabeler
from sim.labels.segmentation import Segmenter

G = mujoco.mjtGeom
VOXEL = 0.01
BOUNDS = np.array([[-0.2, -0.2, 0.0], [0.2, 0.2, 0.2]])


def _reference_occupancy(model, data, ids, shapes):
    """Every voxel centre tested against every labelled geom, one geom at a time, over the whole grid."""
    shape = tuple(np.rint((BOUNDS[1] - BOUNDS[0]) / VOXEL).astype(int))
    key = (ids.geom_semantic.astype(np.uint32) << 16) | ids.geom_instance.astype(np.uint32)
    keys = np.zeros(shape, np.uint32)
    dx, dy, dz = (BOUNDS[0, a] + (np.arange(shape[a]) + 0.5) * VOXEL for a in range(3))
    for g in np.flatnonzero((ids.geom_semantic > 0) & (model.geom_type != PLANE)):
        R, p = data.geom_xmat[g].reshape(3, 3), data.geom_xpos[g]
        x, y, z = (R[0, a] * (dx - p[0])[:, None, None] + R[1, a] * (dy - p[1])[None, :, None]
                   + R[2, a] * (dz - p[2])[None, None, :] for a in range(3))
        keys = np.maximum(keys, np.where(shapes.contains(int(g), x, y, z), key[g], 0).astype(np.uint32))
    return (keys >> 16).astype(np.uint8), (keys & 0xFFFF).astype(np.uint16)


def _mixed_scene():
    """Every geom type, turned, overlapping, one body partly outside the grid, and a fixed table."""
    spec = new_spec()
    ring = trimesh.creation.annulus(r_min=0.02, r_max=0.05, height=0.04, sections=48)
    spec.add_mesh(name="ring", uservert=ring.vertices.ravel().tolist(), userface=ring.faces.ravel().tolist())
    hull = trimesh.creation.icosphere(subdivisions=1, radius=0.04)
    spec.add_mesh(name="hull", uservert=hull.vertices.ravel().tolist(), userface=hull.faces.ravel().tolist())
    table = spec.worldbody.add_body(name="table", pos=[0, 0, 0.03])
    table.add_geom(type=G.mjGEOM_BOX, size=[0.15, 0.1, 0.03])
    add_free_body(spec, "a", (0.02, 0.01, 0.08), [
        box([0.04, 0.03, 0.02]),
        {"type": G.mjGEOM_SPHERE, "size": [0.035, 0, 0], "pos": [0.03, 0, 0.01]},
        {"type": G.mjGEOM_CAPSULE, "size": [0.015, 0.04, 0], "pos": [-0.02, 0.02, 0], "quat": [0.9, 0.3, 0.2, 0]},
    ])
    add_free_body(spec, "b", (-0.05, -0.04, 0.1), [
        {"type": G.mjGEOM_CYLINDER, "size": [0.03, 0.05, 0]},
        {"type": G.mjGEOM_ELLIPSOID, "size": [0.05, 0.02, 0.03], "pos": [0.02, 0.0, 0.03]},
        {"type": G.mjGEOM_MESH, "meshname": "ring", "pos": [0.0, 0.03, -0.02]},
    ])
    add_free_body(spec, "c", (0.17, 0.15, 0.19), [      # crosses the grid's corner
        {"type": G.mjGEOM_MESH, "meshname": "hull"},
        {"type": G.mjGEOM_CAPSULE, "size": [0.02, 0.06, 0]},
    ])
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data, LabelIds.build(model, [("a", "a"), ("b", "b"), ("c", "c")], {"table": ["table"]})


def test_batched_occupancy_matches_a_per_geom_full_grid_reference():
    model, data, ids = _mixed_scene()
    labeler = OccupancyLabeler(model, ids, BOUNDS, VOXEL)
    rng = np.random.default_rng(3)
    for pose in range(4):
        if pose:        # turn and shift the bodies (their geoms overlap each other and the table)
            for name in ("a", "b", "c"):
                q = rng.normal(size=4)
                centre = {"a": (0.02, 0.01, 0.08), "b": (-0.05, -0.04, 0.1), "c": (0.17, 0.15, 0.19)}[name]
                place(model, data, name, np.add(centre, rng.normal(0, 0.02, 3)), q / np.linalg.norm(q))
        grid = labeler.capture(data)
        semantic, instance = _reference_occupancy(model, data, ids, labeler.shapes)
        assert grid.semantic.dtype == np.uint8 and grid.instance.dtype == np.uint16
        np.testing.assert_array_equal(grid.semantic, semantic)
        np.testing.assert_array_equal(grid.instance, instance)
        assert len(np.unique(instance)) == 4          # every object fills voxels
    place(model, data, "c", (3.0, 3.0, 3.0))          # out of the grid: its voxels are freed
    grid = labeler.capture(data)
    assert not (grid.instance == 3).any()
    np.testing.assert_array_equal(grid.semantic, _reference_occupancy(model, data, ids, labeler.shapes)[0])


def _reference_boxes(instance, count):
    xyxy = np.full((count, 4), np.nan, np.float32)
    pixels = np.zeros(count, np.int64)
    for i in range(1, count + 1):
        rows, cols = np.nonzero(instance == i)
        if rows.size:
            xyxy[i - 1] = cols.min(), rows.min(), cols.max() + 1, rows.max() + 1
            pixels[i - 1] = rows.size
    return xyxy, pixels


def test_mask_boxes_match_a_per_instance_reference():
    rng = np.random.default_rng(0)
    masks = [np.zeros((7, 9), np.uint16)]                     # empty
    corner = np.zeros((7, 9), np.uint16)
    corner[0, 0], corner[6, 8], corner[0, 8] = 1, 1, 3        # single pixels on the corners
    masks.append(corner)
    for _ in range(20):
        mask = np.zeros((rng.integers(1, 30), rng.integers(1, 40)), np.uint16)
        for label in rng.integers(1, 6, rng.integers(0, 6)):
            (r0, r1), (c0, c1) = np.sort(rng.integers(0, mask.shape[0] + 1, 2)), np.sort(rng.integers(0, mask.shape[1] + 1, 2))
            mask[r0:r1, c0:c1] = label
        masks.append(mask)
        masks.append(mask[::-1, 1:])                          # a non-contiguous view
    for mask in masks:
        xyxy, pixels = mask_boxes(mask, 5)
        ref_xyxy, ref_pixels = _reference_boxes(mask, 5)
        assert xyxy.dtype == np.float32 and pixels.dtype == np.int64
        np.testing.assert_array_equal(xyxy, ref_xyxy)
        np.testing.assert_array_equal(pixels, ref_pixels)
    with pytest.raises(ValueError, match="above the 2 objects"):
        mask_boxes(corner, 2)


def _reference_visibility(labeler, data, cam, instance):
    """The sample's pixel or a 4-neighbour, each clipped to the image, shows the sample's object."""
    K, R, t = camera_projection(labeler.model, data, cam, WIDTH, HEIGHT)
    pc = labeler.samples.world(data) @ R.T + t
    ahead = pc[:, 2] > 1e-9
    z = np.where(ahead, pc[:, 2], 1.0)
    u = np.floor(K[0, 0] * pc[:, 0] / z + K[0, 2]).astype(np.int64)
    v = np.floor(K[1, 1] * pc[:, 1] / z + K[1, 2]).astype(np.int64)
    inside = ahead & (u >= 0) & (u < WIDTH) & (v >= 0) & (v < HEIGHT)
    seen = np.zeros(len(u), bool)
    for du, dv in [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)]:
        seen |= instance[np.clip(v + dv, 0, HEIGHT - 1), np.clip(u + du, 0, WIDTH - 1)] == labeler.samples.instance
    seen &= inside
    n = labeler.samples.count
    return (np.bincount(labeler.samples.instance[seen], minlength=n + 1)[1:] / labeler.samples.per_object).astype(np.float32)


@pytest.mark.parametrize("pos", [(0.0, 0.0, 0.05), (0.29, 0.0, 0.05), (-0.27, 0.0, 0.12), (0.0, 0.0, -0.05),
                                 (0.0, -1.0, 0.05)])
def test_visibility_matches_the_clipped_neighbour_reference(pos):
    # the cube centred, cut by the right, left / top and bottom borders, and behind the camera
    model, data, ids = cube_scene()
    labeler = Box2DLabeler(model, ids)
    cam = model.camera("cam").id
    place(model, data, "target", pos)
    instance = Segmenter(ids).masks(render_seg(model, data)).instance
    boxes = labeler.capture(data, cam, instance)
    np.testing.assert_array_equal(boxes.visibility, _reference_visibility(labeler, data, cam, instance))


def test_surface_samples_follow_the_pose_between_calls():
    model, data, ids = cube_scene()
    samples = Box2DLabeler(model, ids).samples
    first = samples.world(data)
    assert not first.flags.writeable and samples.world(data) is first        # same pose: reused
    place(model, data, "target", (0.1, 0.0, 0.05))
    moved = samples.world(data)
    np.testing.assert_allclose(moved - first, np.tile([0.1, 0.0, 0.0], (len(first), 1)), atol=1e-12)
    rot = data.geom_xmat[samples.geom].reshape(-1, 3, 3)
    np.testing.assert_array_equal(moved, data.geom_xpos[samples.geom] + np.einsum("nij,nj->ni", rot, samples.local))
