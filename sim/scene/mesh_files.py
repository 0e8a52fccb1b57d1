"""Object parts from mesh files, loaded with trimesh.

    objects:
      mug: {mesh: meshes/mug.obj, mass: 0.3}                     # relative to the task file, or absolute
      vase: {mesh: {file: /data/vase.stl, scale: 0.001}, density: 600}
      kettle:
        parts:                                                   # several meshes make a concave object
          - {mesh: {file: kettle_body.stl, scale: 0.001}}
          - {mesh: {file: kettle_handle.stl, scale: 0.001}, pos: [0.09, 0, 0.02]}

The mesh is scaled (a number or one per axis) and centred on its bounding-box centre, which is
the part's frame. Each mesh part collides as its convex hull, and the hull is also what is
rendered and what the tactile rays meet (the compiled geom), so the three always agree. A hull,
not a convex decomposition: MuJoCo collides every mesh geom as its convex hull anyway; a
decomposition needs a further library (CoACD or V-HACD, not a b2d dependency) whose pieces depend
on its settings; and the containers the predicates look into are better built from the generated
open shapes, whose cavity is exact. A concave object is declared as several mesh parts, one per
convex piece, as a person would split it (or as a decomposition tool run offline would).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial import ConvexHull, QhullError

from sim.errors import SpecError

MESH_KEYS = ("file", "scale")
MIN_HULL_VOLUME_M3 = 1e-9     # a flat or degenerate mesh has no hull to collide with (1 mm^3)


@dataclass(frozen=True)
class MeshRef:
    """A mesh file as a part uses it: absolute path, scale per axis and the file's content hash
    (so two loads of a changed file are two meshes)."""
    file: str
    scale: tuple[float, float, float]
    sha256: str


def _scale(path, field: str, raw) -> tuple[float, float, float]:
    values = [raw] * 3 if isinstance(raw, (int, float)) and not isinstance(raw, bool) else raw
    ok = isinstance(values, (list, tuple)) and len(values) == 3 and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0 for v in values)
    if not ok:
        raise SpecError(path, field, "a positive scale: one number or [sx, sy, sz]", raw)
    return tuple(float(v) for v in values)


def parse_mesh(path, field: str, raw) -> MeshRef:
    """`mesh: file` or `mesh: {file, scale}`; the file is relative to the task file or absolute.
    The mesh is loaded here, so a missing or unreadable file fails when the task loads."""
    if isinstance(raw, str):
        raw, file_field = {"file": raw}, field
    elif isinstance(raw, dict):
        for key in raw:
            if key not in MESH_KEYS:
                raise SpecError(path, f"{field}.{key}", f"a mesh key {list(MESH_KEYS)}")
        file_field = f"{field}.file"
    else:
        raise SpecError(path, field, "a mesh file path or a mapping {file, scale}", raw)
    name = raw.get("file")
    if not isinstance(name, str) or not name:
        raise SpecError(path, file_field, "a mesh file path", name)
    file = Path(name) if Path(name).is_absolute() else Path(path).resolve().parent / name
    if not file.is_file():
        raise SpecError(path, file_field, "an existing mesh file (relative to the task file, or absolute)",
                        str(file))
    ref = MeshRef(str(file), _scale(path, f"{field}.scale", raw.get("scale", 1.0)),
                  hashlib.sha256(file.read_bytes()).hexdigest())
    try:
        load_hull(ref)
    except ValueError as err:
        raise SpecError(path, file_field, f"a mesh file trimesh can read as a solid ({err})", str(file)) from err
    return ref


def convex_hull(points: np.ndarray) -> trimesh.Trimesh:
    """The convex hull of points, faces wound outwards by qhull's own facet normals (trimesh's
    hull repairs winding through networkx, which b2d does not install)."""
    hull = ConvexHull(points)
    faces = hull.simplices.copy()
    corners = points[faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    inward = np.einsum("ij,ij->i", normals, hull.equations[:, :3]) < 0
    faces[inward] = faces[inward][:, ::-1]
    used, faces = np.unique(faces, return_inverse=True)
    return trimesh.Trimesh(vertices=points[used], faces=faces.reshape(-1, 3), process=False)


@lru_cache(maxsize=128)
def load_hull(ref: MeshRef) -> trimesh.Trimesh:
    """The scaled mesh's convex hull, centred on its bounding-box centre (shared: do not modify)."""
    try:
        mesh = trimesh.load(ref.file, force="mesh")
    except Exception as err:      # trimesh raises many types for files it cannot parse
        raise ValueError(f"{type(err).__name__}: {err}") from err
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.vertices) < 4:
        raise ValueError("no triangles found")
    points = np.asarray(mesh.vertices, dtype=float) * np.asarray(ref.scale)
    try:
        hull = convex_hull(points)
    except QhullError as err:     # all points on a plane or a line
        raise ValueError("its points span no volume") from err
    if not hull.volume > MIN_HULL_VOLUME_M3:
        raise ValueError(f"its convex hull has no volume ({hull.volume:.3g} m^3)")
    hull.apply_translation(-hull.bounds.mean(axis=0))
    return hull
