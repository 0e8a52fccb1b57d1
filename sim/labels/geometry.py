"""Geometry of compiled MuJoCo geoms for the labels: bounds in any frame, point containment and
surface samples, for the primitives (analytic) and for mesh geoms.

A geom's local frame is MuJoCo's: primitives are centred on it (cylinders and capsules along z, size
= half sizes); mesh vertices (`model.mesh_vert`) are already expressed in it. Planes are infinite
half-spaces and carry no finite shape: callers leave them out. A mesh counts as solid: a convex mesh
is its hull's half-spaces (what MuJoCo collides); a watertight non-convex mesh uses trimesh's
containment test; any other mesh falls back to its convex hull.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import mujoco
import numpy as np
import trimesh
from scipy.spatial import ConvexHull

from sim.unit_shapes import unit_icosphere

G = mujoco.mjtGeom
BOX, SPHERE, ELLIPSOID, CYLINDER, CAPSULE, MESH, PLANE = (int(G.mjGEOM_BOX), int(G.mjGEOM_SPHERE),
                                                          int(G.mjGEOM_ELLIPSOID), int(G.mjGEOM_CYLINDER),
                                                          int(G.mjGEOM_CAPSULE), int(G.mjGEOM_MESH),
                                                          int(G.mjGEOM_PLANE))
PRIMITIVE_TYPES = (BOX, SPHERE, ELLIPSOID, CYLINDER, CAPSULE)
SOLID_TYPES = PRIMITIVE_TYPES + (MESH,)
HULL_TOLERANCE = 1e-9
SURFACE_SECTIONS = 24     # facets round cylinders and capsules for surface samples
SURFACE_SPHERE_LEVEL = 2  # icosphere subdivisions of spheres and ellipsoids for surface samples


def primitive_contains(kind: int, size: np.ndarray, x, y, z) -> np.ndarray:
    """Whether points with local coordinates (x, y, z) are inside or on a primitive of type `kind`:
    `size` is one geom's [3] (MuJoCo half sizes) or [3, N], a size per point (points of several geoms
    of that type tested at once)."""
    s0, s1, s2 = size
    if kind == BOX:
        return (np.abs(x) <= s0) & (np.abs(y) <= s1) & (np.abs(z) <= s2)
    if kind == SPHERE:
        return x * x + y * y + z * z <= s0 * s0
    if kind == ELLIPSOID:
        return (x / s0) ** 2 + (y / s1) ** 2 + (z / s2) ** 2 <= 1.0
    if kind == CYLINDER:
        return (x * x + y * y <= s0 * s0) & (np.abs(z) <= s1)
    if kind == CAPSULE:
        beyond = np.maximum(np.abs(z) - s1, 0.0)      # distance past the segment's end along z
        return x * x + y * y + beyond * beyond <= s0 * s0
    raise ValueError(f"geom type {kind} is not a primitive")


def check_solid(model: mujoco.MjModel, geoms) -> None:
    """Fail, naming the geom, on a geom type the labels cannot fill (height fields, SDFs)."""
    for g in geoms:
        if int(model.geom_type[g]) not in SOLID_TYPES:
            name = model.geom(g).name or f"#{g}"
            kind = mujoco.mjtGeom(int(model.geom_type[g])).name
            raise ValueError(f"geom '{name}': type {kind} is not supported by the labels "
                             f"(supported: box, sphere, ellipsoid, cylinder, capsule, mesh)")


@dataclass
class MeshShape:
    """One compiled mesh in its geom's local frame."""

    vertices: np.ndarray    # [V, 3]
    faces: np.ndarray       # [F, 3]

    @cached_property
    def hull(self) -> ConvexHull:
        return ConvexHull(self.vertices)

    @cached_property
    def hull_vertices(self) -> np.ndarray:
        return self.vertices[self.hull.vertices]

    @cached_property
    def trimesh(self) -> trimesh.Trimesh:
        return trimesh.Trimesh(self.vertices, self.faces, process=True)

    @cached_property
    def solid_by_hull(self) -> bool:
        """Containment by the hull's half-spaces: convex meshes, and meshes that enclose no volume."""
        mesh = self.trimesh
        return bool(mesh.is_convex or not mesh.is_watertight)

    def contains(self, points: np.ndarray) -> np.ndarray:
        if self.solid_by_hull:
            eq = self.hull.equations        # [P, 4]: n.x + d <= 0 inside
            return np.all(points @ eq[:, :3].T + eq[:, 3] <= HULL_TOLERANCE, axis=1)
        return self.trimesh.contains(points)


class GeomShapes:
    """Shape data of a model's geoms, with compiled meshes converted once."""

    def __init__(self, model: mujoco.MjModel):
        self.model = model
        self.type = model.geom_type.astype(int)
        self.size = model.geom_size.copy()
        self._meshes: dict[int, MeshShape] = {}

    def mesh(self, g: int) -> MeshShape:
        mid = int(self.model.geom_dataid[g])
        if mid not in self._meshes:
            m = self.model
            v0, nv = m.mesh_vertadr[mid], m.mesh_vertnum[mid]
            f0, nf = m.mesh_faceadr[mid], m.mesh_facenum[mid]
            self._meshes[mid] = MeshShape(m.mesh_vert[v0:v0 + nv].astype(float), m.mesh_face[f0:f0 + nf].copy())
        return self._meshes[mid]

    def bounds(self, geoms: np.ndarray, rot: np.ndarray, pos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Exact axis-aligned bounds [G, 3] (lo, hi) of each geom in a frame where the geom's local
        frame has rotation `rot` [G, 3, 3] and origin `pos` [G, 3]."""
        kind, size = self.type[geoms], self.size[geoms]
        half = np.zeros((len(geoms), 3))
        r, h = size[:, :1], size[:, 1:2]
        axis_z = np.abs(rot[:, :, 2])                     # |local z| in the frame, per axis
        sel = kind == BOX
        half[sel] = np.einsum("gij,gj->gi", np.abs(rot[sel]), size[sel])
        sel = kind == SPHERE
        half[sel] = r[sel]
        sel = kind == ELLIPSOID
        half[sel] = np.sqrt(np.einsum("gij,gj->gi", rot[sel] ** 2, size[sel] ** 2))
        sel = kind == CYLINDER
        half[sel] = r[sel] * np.sqrt(np.clip(1.0 - axis_z[sel] ** 2, 0.0, None)) + h[sel] * axis_z[sel]
        sel = kind == CAPSULE
        half[sel] = r[sel] + h[sel] * axis_z[sel]
        lo, hi = pos - half, pos + half
        for k in np.flatnonzero(kind == MESH):
            pts = self.mesh(int(geoms[k])).hull_vertices @ rot[k].T
            lo[k], hi[k] = pos[k] + pts.min(axis=0), pos[k] + pts.max(axis=0)
        return lo, hi

    def contains(self, g: int, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        """Whether points with local coordinates (x, y, z) (arrays of one shape) are inside or on geom g."""
        kind = self.type[g]
        if kind == MESH:
            points = np.stack([np.ravel(x), np.ravel(y), np.ravel(z)], axis=1)
            return self.mesh(g).contains(points).reshape(np.shape(x))
        if kind in PRIMITIVE_TYPES:
            return primitive_contains(kind, self.size[g], x, y, z)
        check_solid(self.model, [g])
        raise AssertionError("unreachable")

    def surface(self, g: int) -> trimesh.Trimesh:
        """The geom's surface as a triangle mesh in its local frame (for area-uniform samples)."""
        kind, s = self.type[g], self.size[g]
        if kind == BOX:
            return trimesh.creation.box(extents=2.0 * s)
        if kind in (SPHERE, ELLIPSOID):
            ball = unit_icosphere(SURFACE_SPHERE_LEVEL).copy()     # shared: every render file samples it
            ball.apply_scale(s if kind == ELLIPSOID else np.full(3, s[0]))
            return ball
        if kind == CYLINDER:
            return trimesh.creation.cylinder(radius=s[0], height=2.0 * s[1], sections=SURFACE_SECTIONS)
        if kind == CAPSULE:
            return trimesh.creation.capsule(height=2.0 * s[1], radius=s[0],
                                            count=[SURFACE_SECTIONS, SURFACE_SECTIONS])
        if kind == MESH:
            shape = self.mesh(g)
            return trimesh.Trimesh(shape.vertices, shape.faces, process=False)
        check_solid(self.model, [g])
        raise AssertionError("unreachable")
