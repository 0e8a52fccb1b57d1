"""Objects from mesh files: loaded, scaled and centred, collided as their convex hull, weighed by
density or mass, resting on the table, and met by the tactile rays; bad files fail naming the task
file, the field and the path. The meshes are written by the tests with trimesh."""

import copy

import mujoco
import numpy as np
import pytest
import trimesh
import yaml

from sim import physics
from sim.errors import SpecError
from sim.registry import catalog_path, load_yaml
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample
from sim.scene.state import SceneObserver
from sim.tasks import parse_task
from tactile.targets import geom_mesh, geom_raycaster, target_geoms

BASE = load_yaml(catalog_path("tasks", "citrus_plate_loading"))
BLOCK_EXTENTS = np.array([0.05, 0.04, 0.08])
CONE_RADIUS, CONE_HEIGHT, CONE_Z_SCALE = 0.03, 0.04, 2.0
DENSITY = 500.0


def _write_meshes(tmp_path):
    (tmp_path / "meshes").mkdir()
    # an off-centre block: loading centres it on its bounding box
    block = trimesh.creation.box(extents=BLOCK_EXTENTS)
    block.apply_translation([0.3, -0.2, 0.5])
    block.export(tmp_path / "meshes" / "block.obj")
    cone = trimesh.creation.cone(radius=CONE_RADIUS, height=CONE_HEIGHT, sections=48)
    cone.export(tmp_path / "cone.stl")
    return tmp_path / "cone.stl"


def _task_file(tmp_path, mutate=None):
    cone = _write_meshes(tmp_path)
    raw = copy.deepcopy(BASE)
    raw["objects"]["lemon_1"] = {"mesh": "meshes/block.obj", "density": DENSITY, "rgba": [0.9, 0.8, 0.2, 1],
                                 "pose": {"xy": [0.2, -0.06]}}
    raw["objects"]["orange_1"] = {"mesh": {"file": str(cone), "scale": [1, 1, CONE_Z_SCALE]}, "mass": 0.2,
                                  "pose": {"xy": [0.3, 0.06]}}
    if mutate:
        mutate(raw)
    path = tmp_path / "mesh_task.yaml"
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    return path


def _load(path):
    return parse_task(load_yaml(path), path)


def test_mesh_objects_are_scaled_centred_and_weighed(tmp_path):
    task = _load(_task_file(tmp_path))
    block, cone = task.objects["lemon_1"], task.objects["orange_1"]
    assert np.allclose(block.half_extents, BLOCK_EXTENTS / 2, atol=1e-6)      # relative path, centred
    assert block.mass == pytest.approx(DENSITY * np.prod(BLOCK_EXTENTS), rel=1e-6)
    cone_half = [CONE_RADIUS, CONE_RADIUS, CONE_HEIGHT * CONE_Z_SCALE / 2]
    assert np.allclose(cone.half_extents, cone_half, atol=2e-4)               # absolute path, per-axis scale
    assert cone.mass == 0.2 and cone.rest_height == pytest.approx(cone_half[2], abs=1e-6)


def test_mesh_objects_collide_as_their_hull_rest_on_the_table_and_are_tactile_targets(tmp_path):
    task = _load(_task_file(tmp_path))
    scene = build_scene(task, task.paper_embodiment, demonstration_sample(task, 0))
    model = scene.model
    data = scene.home_data()
    for _ in range(physics.CONTROL_HZ):         # 1 s with the robot holding home
        physics.step_control(model, data, scene.layout.home_ctrl)
    states = SceneObserver(scene).object_states(data)
    for name, half_z in (("lemon_1", BLOCK_EXTENTS[2] / 2), ("orange_1", CONE_HEIGHT)):
        gid = model.geom(name).id
        assert model.geom_type[gid] == mujoco.mjtGeom.mjGEOM_MESH
        assert model.body_mass[model.body(name).id] == pytest.approx(task.objects[name].mass)
        # standing on the table: the bounding-box bottom at the tabletop, still upright
        assert states[name].pos[2] - half_z == pytest.approx(scene.table_height, abs=2e-3), name
        assert data.xmat[model.body(name).id][8] > np.cos(np.deg2rad(2)), name     # tilt under 2 degrees
        assert gid in [g for _, g in target_geoms(model, scene.object_names)]
        # a tactile ray straight down onto the object meets its top where the hull is
        top = states[name].pos + [0, 0, half_z]
        rot = data.geom_xmat[gid].reshape(3, 3)
        origin = rot.T @ (top + [0, 0, 0.05] - data.geom_xpos[gid])
        hit = geom_raycaster(model, gid).depth(origin[None], (rot.T @ [0, 0, -1.0])[None], 0.2)[0]
        assert hit == pytest.approx(0.05, abs=1e-4), name
        # the compiled mesh (MuJoCo moves it to its inertial frame) is the hull, back in the body frame
        rot_geom = np.zeros(9)
        mujoco.mju_quat2Mat(rot_geom, model.geom_quat[gid])
        vertices = geom_mesh(model, gid).vertices @ rot_geom.reshape(3, 3).T + model.geom_pos[gid]
        half = task.objects[name].half_extents
        assert np.allclose([vertices.min(axis=0), vertices.max(axis=0)], [-half, half], atol=1e-5), name


@pytest.mark.parametrize("mutate,field,expected", [
    (lambda r: r["objects"]["lemon_1"].update(mesh="meshes/missing.obj"),
     "objects.lemon_1.mesh", "an existing mesh file"),
    (lambda r: r["objects"]["orange_1"]["mesh"].update(file="/nonexistent/cone.stl"),
     "objects.orange_1.mesh.file", "an existing mesh file"),
    (lambda r: r["objects"]["lemon_1"].update(mesh="garbage.obj"),
     "objects.lemon_1.mesh", "a mesh file trimesh can read"),
    (lambda r: r["objects"]["lemon_1"].update(mesh="flat.obj"),
     "objects.lemon_1.mesh", "a mesh file trimesh can read"),
    (lambda r: r["objects"]["orange_1"]["mesh"].update(scale=[1, 0, 1]),
     "objects.orange_1.mesh.scale", "a positive scale"),
    (lambda r: r["objects"]["orange_1"]["mesh"].update(units="mm"),
     "objects.orange_1.mesh.units", "a mesh key"),
    (lambda r: r["objects"]["lemon_1"].update(shape="box", size=[0.1, 0.1, 0.1]),
     "objects.lemon_1", "exactly one of"),
    (lambda r: r["objects"]["lemon_1"].update(mass=0.3),
     "objects.lemon_1", "one of 'mass' (kg) or 'density'"),
    (lambda r: r["objects"]["lemon_1"].update(density=1e5),
     "objects.lemon_1.density", "a number in [10.0, 25000.0]"),
])
def test_bad_mesh_input_names_the_file_the_field_and_the_path(tmp_path, mutate, field, expected):
    (tmp_path / "garbage.obj").write_text("this is not a mesh\n")
    flat = trimesh.Trimesh(vertices=[[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0.1, 0.1, 0]],
                           faces=[[0, 1, 2], [1, 3, 2]])
    flat.export(tmp_path / "flat.obj")
    path = _task_file(tmp_path, mutate)
    with pytest.raises(SpecError) as err:
        _load(path)
    assert err.value.path == str(path)
    assert err.value.field == field and expected in err.value.expected, str(err.value)
    if "mesh" in field and "scale" not in field and "units" not in field:
        assert str(tmp_path) in str(err.value) or "/nonexistent/" in str(err.value)    # the mesh path
