"""3D boxes, occupancy and geom bounds with analytic answers on tiny MjSpec scenes."""

import mujoco
import numpy as np
import pytest
import trimesh

from label_scenes import add_free_body, box, cube_scene, new_spec, place
from sim.labels.box3d import Box3DLabeler
from sim.labels.geometry import GeomShapes
from sim.labels.ids import LabelIds
from sim.labels.occupancy import OccupancyLabeler

G = mujoco.mjtGeom
VOXEL = 0.01
BOUNDS = [[-0.2, -0.2, 0.0], [0.2, 0.2, 0.2]]


def _compile(spec, objects, parts=None):
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data, LabelIds.build(model, objects, parts or {})


def _quat(axis, angle_deg):
    q = np.zeros(4)
    axis = np.asarray(axis, float)
    mujoco.mju_axisAngle2Quat(q, axis / np.linalg.norm(axis), np.deg2rad(angle_deg))
    return q


# ---------------------------------------------------------------- 3D boxes


def test_box3d_matches_the_placed_compound_body_exactly():
    spec = new_spec()
    add_free_body(spec, "tool", (0, 0, 0.5), [
        box([0.04, 0.02, 0.01], pos=(0.05, 0, 0)),
        {"type": G.mjGEOM_SPHERE, "size": [0.02, 0, 0], "pos": [-0.05, 0, 0]},
        # a cylinder turned onto the body's y axis: extents r, h, r
        {"type": G.mjGEOM_CYLINDER, "size": [0.01, 0.03, 0], "pos": [0, 0, 0.02], "quat": list(_quat([1, 0, 0], 90))},
    ])
    model, data, ids = _compile(spec, [("tool", "tool")])
    pos, quat = np.array([0.3, -0.2, 0.9]), _quat([0.3, -0.5, 0.8], 130)
    place(model, data, "tool", pos, quat)
    boxes = Box3DLabeler(model, ids).capture(data)
    local_centre = np.array([0.01, 0.0, 0.005])              # x [-0.07, 0.09], y [-0.03, 0.03], z [-0.02, 0.03]
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, quat)
    np.testing.assert_allclose(boxes.center_world[0], pos + R.reshape(3, 3) @ local_centre, atol=1e-12)
    np.testing.assert_allclose(boxes.size_lwh[0], [0.16, 0.06, 0.05], atol=1e-12)
    np.testing.assert_allclose(boxes.quat_world[0], quat if quat[0] >= 0 else -quat, atol=1e-12)
    place(model, data, "tool", pos, -quat)                   # the same pose, other quaternion sign
    assert Box3DLabeler(model, ids).capture(data).quat_world[0, 0] > 0


def test_box3d_follows_an_articulated_link():
    spec = new_spec()
    base = spec.worldbody.add_body(name="cabinet", pos=[0, 0, 0.3])
    base.add_geom(type=G.mjGEOM_BOX, size=[0.1, 0.05, 0.01])
    link = base.add_body(name="cabinet/flag", pos=[0.1, 0, 0])
    link.add_joint(name="cabinet/flag", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    link.add_geom(type=G.mjGEOM_BOX, size=[0.05, 0.01, 0.01], pos=[0.05, 0, 0])
    model, data, ids = _compile(spec, [("cabinet", "cabinet")])
    labeler = Box3DLabeler(model, ids)
    flat = labeler.capture(data)
    np.testing.assert_allclose(flat.size_lwh[0], [0.3, 0.1, 0.02], atol=1e-12)       # x from -0.1 to 0.2
    np.testing.assert_allclose(flat.center_world[0], [0.05, 0, 0.3], atol=1e-12)
    data.qpos[model.joint("cabinet/flag").qposadr[0]] = np.pi / 2                      # flag turned onto +y
    mujoco.mj_kinematics(model, data)
    turned = labeler.capture(data)
    # base x +-0.1, y +-0.05; flag x 0.09..0.11, y 0..0.1
    np.testing.assert_allclose(turned.size_lwh[0], [0.21, 0.15, 0.02], atol=1e-12)
    np.testing.assert_allclose(turned.center_world[0], [0.005, 0.025, 0.3], atol=1e-12)


@pytest.mark.parametrize("kind,size", [(G.mjGEOM_ELLIPSOID, [0.03, 0.05, 0.02]), (G.mjGEOM_CYLINDER, [0.03, 0.05, 0]),
                                       (G.mjGEOM_CAPSULE, [0.02, 0.04, 0]), (G.mjGEOM_BOX, [0.03, 0.05, 0.02])])
def test_geom_bounds_are_tight_for_turned_primitives(kind, size):
    spec = new_spec()
    spec.worldbody.add_body(name="b").add_geom(type=kind, size=size)
    model, _, _ = _compile(spec, [])
    rng = np.random.default_rng(3)
    # dense points of the exact surface, from which the analytic bounds must not differ
    s = np.asarray(size, float)
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 721), np.linspace(-np.pi / 2, np.pi / 2, 361))
    sphere = np.stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)], axis=-1).reshape(-1, 3)
    if kind == G.mjGEOM_ELLIPSOID:
        surface = sphere * s
    elif kind == G.mjGEOM_BOX:
        surface = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)]) * s
    elif kind == G.mjGEOM_CYLINDER:
        ring = np.stack([np.cos(u[0]), np.sin(u[0]), np.zeros_like(u[0])], axis=1) * s[0]
        surface = np.concatenate([ring + [0, 0, s[1]], ring - [0, 0, s[1]]])
    else:
        surface = np.concatenate([sphere * s[0] + [0, 0, s[1]], sphere * s[0] - [0, 0, s[1]]])
    shapes = GeomShapes(model)
    for _ in range(5):
        q = rng.normal(size=4)
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, q / np.linalg.norm(q))
        R = R.reshape(3, 3)
        lo, hi = shapes.bounds(np.array([1]), R[None], np.array([[0.1, 0.2, 0.3]]))
        pts = surface @ R.T + [0.1, 0.2, 0.3]
        np.testing.assert_allclose(lo[0], pts.min(axis=0), atol=2e-5)
        np.testing.assert_allclose(hi[0], pts.max(axis=0), atol=2e-5)


# ---------------------------------------------------------------- occupancy


def test_occupancy_of_a_box_fills_exactly_its_voxels():
    model, data, ids = cube_scene()                     # 10 cm cube on the floor at the origin
    grid = OccupancyLabeler(model, ids, BOUNDS, VOXEL).capture(data)
    assert grid.semantic.shape == (40, 40, 20) and grid.semantic.dtype == np.uint8
    occupied = np.argwhere(grid.instance == 1)
    assert len(occupied) == 1000                         # 10 x 10 x 10 voxel centres inside
    np.testing.assert_array_equal(occupied.min(axis=0), [15, 15, 0])
    np.testing.assert_array_equal(occupied.max(axis=0), [24, 24, 9])
    assert set(np.unique(grid.semantic)) == {0, ids.semantic_names.index("cube")}   # the floor plane stays free


def test_occupancy_of_a_sphere_and_a_turned_box_match_their_volumes():
    spec = new_spec()
    add_free_body(spec, "ball", (-0.08, 0.0, 0.1), [{"type": G.mjGEOM_SPHERE, "size": [0.07, 0, 0]}])
    add_free_body(spec, "brick", (0.1, 0.05, 0.1), [box([0.05, 0.03, 0.04])], quat=_quat([0.2, 0.4, 1.0], 37))
    model, data, ids = _compile(spec, [("ball", "ball"), ("brick", "brick")])
    grid = OccupancyLabeler(model, ids, BOUNDS, VOXEL).capture(data)
    ball = (grid.instance == 1).sum()
    # every voxel centre tested directly: the lattice count, then the volume it approximates
    axes = [np.arange(lo, hi, VOXEL) + VOXEL / 2 for lo, hi in zip(*BOUNDS)]
    x, y, z = np.meshgrid(*axes, indexing="ij")
    assert ball == ((x + 0.08) ** 2 + y ** 2 + (z - 0.1) ** 2 <= 0.07 ** 2).sum()
    assert ball == pytest.approx(4 / 3 * np.pi * 0.07 ** 3 / VOXEL ** 3, rel=0.03)   # ~1437 voxels
    assert (grid.instance == 2).sum() == pytest.approx(0.1 * 0.06 * 0.08 / VOXEL ** 3, rel=0.03)


def _mesh_spec(mesh: trimesh.Trimesh, pos):
    spec = new_spec()
    spec.add_mesh(name="shape", uservert=mesh.vertices.ravel().tolist(), userface=mesh.faces.ravel().tolist())
    add_free_body(spec, "thing", pos, [{"type": G.mjGEOM_MESH, "meshname": "shape"}])
    return _compile(spec, [("thing", "thing")])


def test_occupancy_of_mesh_geoms_convex_and_not():
    cube = trimesh.creation.box(extents=[0.1, 0.1, 0.1])
    model, data, ids = _mesh_spec(cube, (0, 0, 0.05))
    assert model.geom_type[1] == G.mjGEOM_MESH
    grid = OccupancyLabeler(model, ids, BOUNDS, VOXEL).capture(data)
    assert (grid.instance == 1).sum() == 1000            # the same voxels as the primitive cube
    ring = trimesh.creation.annulus(r_min=0.04, r_max=0.09, height=0.06, sections=96)
    model, data, ids = _mesh_spec(ring, (0, 0, 0.1))
    grid = OccupancyLabeler(model, ids, BOUNDS, VOXEL).capture(data)
    volume = np.pi * (0.09 ** 2 - 0.04 ** 2) * 0.06
    assert (grid.instance == 1).sum() == pytest.approx(volume / VOXEL ** 3, rel=0.03)
    assert grid.instance[20, 20, 10] == 0                # the hole stays free (not the convex hull)


def test_occupancy_of_world_fixed_parts_and_overlap_priority():
    spec = new_spec()
    table = spec.worldbody.add_body(name="table", pos=[0, 0, 0.05])
    table.add_geom(type=G.mjGEOM_BOX, size=[0.1, 0.1, 0.05])
    add_free_body(spec, "cup", (0.1, 0.0, 0.1), [box([0.03, 0.03, 0.03])])   # overlaps the table's corner
    model, data, ids = _compile(spec, [("cup", "cup")], {"table": ["table"]})
    labeler = OccupancyLabeler(model, ids, BOUNDS, VOXEL)
    grid = labeler.capture(data)
    table_id, cup_id = ids.semantic_names.index("table"), ids.semantic_names.index("cup")
    assert (grid.instance == 1).sum() == 216 and (grid.semantic == cup_id).sum() == 216
    assert (grid.semantic == table_id).sum() == 4000 - 3 * 6 * 3    # the cup wins the 54 shared voxels
    assert np.all(grid.instance[grid.semantic == table_id] == 0)
    place(model, data, "cup", (-0.15, 0.0, 0.1))                      # moved off: the table is whole again
    assert (labeler.capture(data).semantic == table_id).sum() == 4000


def test_occupancy_rejects_bounds_that_are_not_whole_voxels():
    model, data, ids = cube_scene()
    with pytest.raises(ValueError, match="whole number of 0.03 m voxels"):
        OccupancyLabeler(model, ids, BOUNDS, 0.03)
    with pytest.raises(ValueError, match="x0 < x1"):
        OccupancyLabeler(model, ids, [[0, 0, 0], [0, 1, 1]], 0.1)


def test_geometry_labels_are_deterministic():
    runs = []
    for _ in range(2):
        model, data, ids = cube_scene(occluder=True)
        place(model, data, "occluder", (0.03, 0.02, 0.09), _quat([1, 1, 0], 20))
        grid = OccupancyLabeler(model, ids, BOUNDS, VOXEL).capture(data)
        boxes = Box3DLabeler(model, ids).capture(data)
        runs.append([grid.semantic, grid.instance, boxes.center_world, boxes.size_lwh, boxes.quat_world])
    for a, b in zip(*runs):
        assert a.tobytes() == b.tobytes()


def test_sphere_and_ellipsoid_surfaces_are_the_icosphere_scaled_every_time():
    """Surface meshes (what 2D boxes sample) start from one cached unit icosphere: asked again, and for
    another size, each is still the unit icosphere scaled to its own geom."""
    spec = new_spec()
    add_free_body(spec, "balls", (0, 0, 0.5), [
        {"type": G.mjGEOM_SPHERE, "size": [0.02, 0, 0]},
        {"type": G.mjGEOM_ELLIPSOID, "size": [0.03, 0.01, 0.02], "pos": [0.1, 0, 0]},
    ])
    model = spec.compile()
    shapes = GeomShapes(model)
    for _ in range(2):
        for g, scale in ((model.geom("balls/0").id, [0.02] * 3), (model.geom("balls/1").id, [0.03, 0.01, 0.02])):
            want = trimesh.creation.icosphere(subdivisions=2)
            want.apply_scale(scale)
            got = shapes.surface(g)
            assert np.array_equal(got.vertices, want.vertices) and np.array_equal(got.faces, want.faces)


def test_an_object_thinner_than_a_voxel_still_occupies_the_voxel_of_its_centre():
    # a 2 mm plate between two layers of voxel centres (1 cm apart) holds none of them: it occupies the voxel
    # holding its centre; a plate that holds centres keeps exactly those
    spec = new_spec()
    add_free_body(spec, "plate", (0.003, 0.003, 0.01), [box([0.05, 0.05, 0.001])])
    add_free_body(spec, "slab", (0.1, 0.1, 0.005), [box([0.03, 0.03, 0.001])])
    model, data, ids = _compile(spec, [("plate", "plate"), ("slab", "slab")])
    grid = OccupancyLabeler(model, ids, BOUNDS, VOXEL).capture(data)
    np.testing.assert_array_equal(np.argwhere(grid.instance == 1), [[20, 20, 1]])
    assert (grid.instance == 2).sum() == 36          # its centres at z 0.005: 6 x 6 of them, nothing added
