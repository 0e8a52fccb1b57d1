"""Ray-cast targets from a compiled MuJoCo model: which geoms, and each as a mesh in its own frame.

Targets are the geoms of the given root bodies (task objects, distractors) and of every body below
them (articulated links), so the robot, the table and the floor can never be hit. Meshes come from
the compiled geoms themselves (type and size), so tactile rays meet exactly what physics collides
with; curved primitives are tessellated finely enough that faceting stays under one fine quantizer
level (5 um).
"""

from __future__ import annotations

import functools
import math

import mujoco
import numpy as np
import trimesh

from sim.unit_shapes import unit_icosphere
from tactile.quantize import FINE_MM_PER_LEVEL
from tactile.raycast import MeshRaycaster

MAX_SAGITTA_M = FINE_MM_PER_LEVEL * 1e-3
MAX_SUBDIVISIONS = 6  # 81,920 faces; meets the bound up to a radius of about 7 cm
MAX_SECTIONS = 1024


def _arc_sections(radius: float) -> int:
    """Segments of a circle of ``radius`` so that the chord-to-arc gap stays under MAX_SAGITTA_M."""
    if radius <= MAX_SAGITTA_M:
        return 8
    return min(MAX_SECTIONS, max(8, math.ceil(math.pi / math.acos(1 - MAX_SAGITTA_M / radius))))


@functools.lru_cache(maxsize=None)
def _unit_facet_depth(level: int) -> float:
    """Deepest point of the unit icosphere's faces below the sphere (their centres; edges vary)."""
    return float(1.0 - np.linalg.norm(unit_icosphere(level).triangles_center, axis=1).min())


def _sphere_subdivisions(radius: float) -> int:
    for level in range(MAX_SUBDIVISIONS + 1):
        if radius * _unit_facet_depth(level) <= MAX_SAGITTA_M:
            return level
    return MAX_SUBDIVISIONS


PRIMITIVES = {mujoco.mjtGeom.mjGEOM_BOX: "box", mujoco.mjtGeom.mjGEOM_SPHERE: "sphere",
              mujoco.mjtGeom.mjGEOM_ELLIPSOID: "ellipsoid", mujoco.mjtGeom.mjGEOM_CYLINDER: "cylinder",
              mujoco.mjtGeom.mjGEOM_CAPSULE: "capsule"}


def primitive_mesh(gtype: int, size) -> trimesh.Trimesh:
    """A MuJoCo primitive (type, half-length sizes) as a triangle mesh in its own frame."""
    size = np.asarray(size, dtype=np.float64)
    if gtype == mujoco.mjtGeom.mjGEOM_BOX:
        return trimesh.creation.box(extents=2 * size)
    if gtype in (mujoco.mjtGeom.mjGEOM_SPHERE, mujoco.mjtGeom.mjGEOM_ELLIPSOID):
        radii = size[:1].repeat(3) if gtype == mujoco.mjtGeom.mjGEOM_SPHERE else size
        mesh = unit_icosphere(_sphere_subdivisions(float(radii.max()))).copy()    # never the shared one
        mesh.apply_scale(radii)
        return mesh
    if gtype == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return trimesh.creation.cylinder(radius=size[0], height=2 * size[1], sections=_arc_sections(size[0]))
    if gtype == mujoco.mjtGeom.mjGEOM_CAPSULE:
        n = _arc_sections(size[0])
        return trimesh.creation.capsule(radius=size[0], height=2 * size[1], count=[n, n])
    raise ValueError(f"no mesh for geom type {mujoco.mjtGeom(gtype).name}")


def _supported_type(model: mujoco.MjModel, geom_id: int) -> int:
    gtype = int(model.geom_type[geom_id])
    if gtype != mujoco.mjtGeom.mjGEOM_MESH and gtype not in PRIMITIVES:
        name = model.geom(geom_id).name or f"#{geom_id}"
        raise ValueError(f"geom '{name}': type {mujoco.mjtGeom(gtype).name} cannot be a tactile target "
                         "(expected box, sphere, ellipsoid, cylinder, capsule or mesh)")
    return gtype


def geom_mesh(model: mujoco.MjModel, geom_id: int) -> trimesh.Trimesh:
    """A geom as a triangle mesh in its own frame (primitives tessellated, meshes as compiled)."""
    gtype = _supported_type(model, geom_id)
    if gtype != mujoco.mjtGeom.mjGEOM_MESH:
        return primitive_mesh(gtype, model.geom_size[geom_id])
    mesh_id = model.geom_dataid[geom_id]
    v0, f0 = model.mesh_vertadr[mesh_id], model.mesh_faceadr[mesh_id]
    vertices = model.mesh_vert[v0 : v0 + model.mesh_vertnum[mesh_id]].astype(np.float64)
    faces = model.mesh_face[f0 : f0 + model.mesh_facenum[mesh_id]]  # indices local to the mesh
    return trimesh.Trimesh(vertices=vertices, faces=faces, process=False)


def geom_mesh_in_body(model: mujoco.MjModel, geom_id: int) -> trimesh.Trimesh:
    """A geom as a triangle mesh in the frame of the body that holds it (compiled pose applied)."""
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, model.geom_quat[geom_id])
    transform = np.eye(4)
    transform[:3, :3] = rot.reshape(3, 3)
    transform[:3, 3] = model.geom_pos[geom_id]
    return geom_mesh(model, geom_id).apply_transform(transform)


@functools.lru_cache(maxsize=256)
def _primitive_raycaster(gtype: int, size: tuple[float, ...]) -> MeshRaycaster:
    return MeshRaycaster(primitive_mesh(gtype, size))


def clear_cache() -> None:
    _primitive_raycaster.cache_clear()
    unit_icosphere.cache_clear()


def geom_raycaster(model: mujoco.MjModel, geom_id: int) -> MeshRaycaster:
    """The geom's ray-cast scene. Primitives are shared by type and size within a process (read-only):
    a fine sphere's BVH takes ~0.1 s to build, and every episode of a task has the same objects."""
    gtype = _supported_type(model, geom_id)
    if gtype == mujoco.mjtGeom.mjGEOM_MESH:
        return MeshRaycaster(geom_mesh(model, geom_id))
    return _primitive_raycaster(gtype, tuple(float(v) for v in model.geom_size[geom_id]))


def target_geoms(model: mujoco.MjModel, root_bodies) -> list[tuple[str, int]]:
    """(name, geom id) of every geom on ``root_bodies`` or below them, in geom order."""
    roots = {model.body(name).id for name in root_bodies}
    owned = set()
    for body in range(model.nbody):
        ancestor = body
        while ancestor not in roots and ancestor != 0:
            ancestor = int(model.body_parentid[ancestor])
        if ancestor in roots:
            owned.add(body)
    out = []
    for gid in range(model.ngeom):
        body = int(model.geom_bodyid[gid])
        if body in owned:
            out.append((model.geom(gid).name or f"{model.body(body).name}#geom{gid}", gid))
    return out
