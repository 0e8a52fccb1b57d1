"""Segmentation and 2D boxes on a 64 x 48 camera looking at a 10 cm cube (tests/labels/label_scenes.py)."""

import numpy as np
import pytest

from label_scenes import (CUBE_HALF, HEIGHT, WIDTH, corners, cube_scene, place, project, render_seg)
from sim.labels.box2d import Box2DLabeler, mask_boxes
from sim.labels.segmentation import Segmenter


def _masks(model, data, ids):
    return Segmenter(ids).masks(render_seg(model, data))


def test_instance_mask_is_the_projected_cube():
    model, data, ids = cube_scene()
    masks = _masks(model, data, ids)
    # level with the cube's centre, the camera sees exactly its front face (y = -0.05)
    front = corners([0, -CUBE_HALF, CUBE_HALF], [CUBE_HALF, 0, CUBE_HALF])
    (u0, v0), (u1, v1) = project(front).min(axis=0), project(front).max(axis=0)
    u, v = np.meshgrid(np.arange(WIDTH) + 0.5, np.arange(HEIGHT) + 0.5)
    expected = (u > u0) & (u < u1) & (v > v0) & (v < v1)
    assert expected.sum() == 100                      # 10 x 10 pixel centres inside the face
    np.testing.assert_array_equal(masks.instance == 1, expected)
    np.testing.assert_array_equal(masks.semantic == ids.semantic_names.index("cube"), expected)
    assert set(np.unique(masks.instance)) == {0, 1}   # the floor belongs to no object


@pytest.mark.parametrize("quat", [(1, 0, 0, 0), (0.9659258, 0, 0, 0.2588190), (0.9238795, 0.2209424, 0.1, 0.3)])
def test_box2d_is_the_projection_of_the_cube_corners(quat):
    model, data, ids = cube_scene()
    quat = np.asarray(quat) / np.linalg.norm(quat)
    place(model, data, "target", (0.02, 0.0, 0.06), quat)
    masks = _masks(model, data, ids)
    boxes = Box2DLabeler(model, ids).capture(data, "cam", masks.instance)
    # the convex cube's silhouette is the hull of its projected corners: same box within a pixel
    R = data.xmat[model.body("target").id].reshape(3, 3)
    pts = data.xpos[model.body("target").id] + (corners([0, 0, 0], [CUBE_HALF] * 3) @ R.T)
    uv = project(pts)
    expected = np.concatenate([uv.min(axis=0), uv.max(axis=0)])
    assert np.all(np.abs(boxes.xyxy[0] - expected) < 1.0), (boxes.xyxy[0], expected)
    assert boxes.visibility[0] > 0.95
    assert boxes.pixels[0] == (masks.instance == 1).sum()


def test_occluded_object_loses_visibility_and_hidden_one_has_no_box():
    model, data, ids = cube_scene(occluder=True)
    labeler = Box2DLabeler(model, ids)
    clear = labeler.capture(data, "cam", _masks(model, data, ids).instance)
    assert clear.visibility[0] > 0.95
    assert np.isnan(clear.xyxy[1]).all() and clear.visibility[1] == 0    # the occluder is parked out of sight
    # a 6 cm wide slab in front of the cube's left half (x < 0.01): about half its silhouette hidden
    place(model, data, "occluder", (-0.02, -0.2, 0.05))
    half = labeler.capture(data, "cam", _masks(model, data, ids).instance)
    assert 0.35 < half.visibility[0] < 0.65
    assert half.xyxy[0, 0] > clear.xyxy[0, 0] + 2 and half.xyxy[0, 2] == clear.xyxy[0, 2]
    # the occluder close to the camera hides the cube entirely
    place(model, data, "occluder", (0.0, -0.5, 0.05))
    hidden = labeler.capture(data, "cam", _masks(model, data, ids).instance)
    assert hidden.visibility[0] == 0 and np.isnan(hidden.xyxy[0]).all() and hidden.pixels[0] == 0


def test_visibility_counts_the_image_border_and_objects_behind_the_camera():
    model, data, ids = cube_scene()
    labeler = Box2DLabeler(model, ids)
    place(model, data, "target", (0.29, 0.0, 0.05))        # partly beyond the right image border
    cut = labeler.capture(data, "cam", _masks(model, data, ids).instance)
    assert cut.xyxy[0, 2] == WIDTH and 0.1 < cut.visibility[0] < 0.9
    place(model, data, "target", (0.0, -1.0, 0.05))        # behind the camera
    behind = labeler.capture(data, "cam", _masks(model, data, ids).instance)
    assert behind.visibility[0] == 0 and np.isnan(behind.xyxy[0]).all()


def test_mask_boxes_use_pixel_edges():
    mask = np.zeros((6, 8), np.uint16)
    mask[2:4, 1:6] = 2
    xyxy, pixels = mask_boxes(mask, 3)
    assert np.isnan(xyxy[0]).all() and np.isnan(xyxy[2]).all()
    np.testing.assert_array_equal(xyxy[1], [1, 2, 6, 4])
    np.testing.assert_array_equal(pixels, [0, 10, 0])


def test_segmentation_rejects_a_malformed_image():
    model, data, ids = cube_scene()
    with pytest.raises(ValueError, match=r"expected \[H, W\] integer geom ids or \[H, W, 2\]"):
        Segmenter(ids).masks(np.zeros((4, 4, 3), np.int32))
    bad = np.zeros((4, 4, 2), np.int32)
    bad[0, 0] = (model.ngeom + 3, 5)
    with pytest.raises(ValueError, match=f"outside -1..{model.ngeom - 1}"):
        Segmenter(ids).masks(bad)


def test_image_labels_are_deterministic():
    model, data, ids = cube_scene(occluder=True)
    place(model, data, "occluder", (-0.02, -0.2, 0.05))
    runs = []
    for _ in range(2):
        masks = _masks(model, data, ids)
        boxes = Box2DLabeler(model, ids).capture(data, "cam", masks.instance)
        runs.append([masks.semantic, masks.instance, boxes.xyxy, boxes.visibility])
    for a, b in zip(*runs):
        assert a.tobytes() == b.tobytes()



def test_geom_id_images_give_the_same_masks():
    """The [H, W] geom-id form (sim.offscreen's depth pass) labels like mujoco.Renderer's (objid, objtype)."""
    model, data, ids = cube_scene(occluder=True)
    place(model, data, "occluder", (-0.02, -0.2, 0.05))
    seg = render_seg(model, data)
    geom_ids = np.where(seg[..., 1] == 5, seg[..., 0], -1).astype(np.int32)     # 5 = mjOBJ_GEOM
    a, b = Segmenter(ids).masks(seg), Segmenter(ids).masks(geom_ids)
    assert set(np.unique(a.instance)) == {0, 1, 2}
    assert a.instance.tobytes() == b.instance.tobytes() and a.semantic.tobytes() == b.semantic.tobytes()


def test_offscreen_renderer_matches_mujoco_renderer():
    """The render stage's one-pass depth + geom ids (sim.offscreen) equal mujoco.Renderer's separate
    depth and segmentation renders, and its RGB the same pixels."""
    import mujoco

    from sim.offscreen import OffscreenRenderer

    model, data, ids = cube_scene(occluder=True)
    place(model, data, "occluder", (-0.02, -0.2, 0.05))
    cam = model.camera("cam").id
    off = OffscreenRenderer(model, WIDTH, HEIGHT)
    try:
        off.update(data, cam)
        rgb = off.color()
        depth, geom_ids = off.depth_and_geoms(True)
        depth_only, none = off.depth_and_geoms(False)
    finally:
        off.close()
    with mujoco.Renderer(model, height=HEIGHT, width=WIDTH) as renderer:
        renderer.update_scene(data, camera=cam)
        expected_rgb = renderer.render()
        renderer.enable_depth_rendering()
        expected_depth = renderer.render()
        renderer.disable_depth_rendering()
    seg = render_seg(model, data)
    assert none is None and depth_only.tobytes() == depth.tobytes()
    np.testing.assert_array_equal(rgb, expected_rgb)
    np.testing.assert_array_equal(depth, expected_depth)
    np.testing.assert_array_equal(geom_ids, np.where(seg[..., 1] == 5, seg[..., 0], -1))   # 5 = mjOBJ_GEOM
    assert set(np.unique(Segmenter(ids).masks(geom_ids).instance)) == {0, 1, 2}
    # level with the cube's centre, the front face is 0.55 m away along the optical axis
    assert depth[HEIGHT // 2, WIDTH // 2 + 3] == pytest.approx(0.6 - CUBE_HALF, abs=1e-4)   # beside the occluder
