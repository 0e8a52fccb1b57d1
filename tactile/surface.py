"""Surface maps: point and inward-normal maps on a regular surface-aligned tactile grid.

A SurfaceMap stores, per grid cell, the nominal contact-surface point (millimetres, attach-body
frame) and the unit inward normal (towards the finger interior); cells without surface are zero,
as in the released Sharpa TacMap assets. Files: ``{group}_point.npy`` and ``{group}_normal.npy``,
float32 (H, W, 3).

Generation casts one ray per cell from the pad's outward side along ``-normal`` onto a contact mesh
(the pad sheet of ``tactile.pads``, or the compiled pad geom, see ``tactile.rig``). Grid: square
window centred on the pad, side ``max(length, width) * (1 + 2 * margin)``; row index increases along
the pad axis, column index along ``axis x normal``. Normals are interpolated from vertex normals
(``smooth_shade`` keeps sharp edges sharp) and oriented against the casting rays.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from tactile.errors import TactileSpecError
from tactile.pads import PadSpec, build_pad_mesh
from tactile.raycast import MeshRaycaster

log = logging.getLogger(__name__)

NATIVE_RESOLUTION = 240
GRID_MARGIN = 0.04  # per side, as a fraction of the pad's longer side (Sharpa maps keep ~10/240)
CAST_HEIGHT_M = 0.01  # rays start this far outside the pad centre plane
SMOOTH_ANGLE_RAD = np.radians(30.0)


@dataclass(frozen=True, eq=False)
class SurfaceMap:
    group: str
    point_mm: np.ndarray  # float32 (H, W, 3), attach-body frame, zero where invalid
    normal: np.ndarray  # float32 (H, W, 3), unit inward, zero where invalid

    @property
    def valid(self) -> np.ndarray:
        return np.linalg.norm(self.normal, axis=-1) > 0.5

    @property
    def shape(self) -> tuple[int, int]:
        return self.point_mm.shape[:2]

    def subsample(self, step: int) -> "SurfaceMap":
        """Every ``step``-th cell in both directions (step 1 = native resolution)."""
        if int(step) != step or step < 1:
            raise ValueError(f"step must be a positive integer, got {step!r}")
        return SurfaceMap(self.group, self.point_mm[::step, ::step], self.normal[::step, ::step])


def surface_map_from_mesh(
    mesh: trimesh.Trimesh,
    center,
    frame: np.ndarray,
    side_m: float,
    resolution: int = NATIVE_RESOLUTION,
    group: str = "pad",
) -> SurfaceMap:
    """Rasterise ``mesh`` onto a square grid of ``resolution`` cells seen along ``-frame[:, 2]``.

    ``frame`` columns are (column direction, row direction, outward normal); ``center`` and the
    mesh are in the attach-body frame (metres).
    """
    center = np.asarray(center, dtype=np.float64)
    frame = np.asarray(frame, dtype=np.float64)
    cell = side_m / resolution
    offsets = (np.arange(resolution) + 0.5) * cell - side_m / 2
    rows, cols = np.meshgrid(offsets, offsets, indexing="ij")
    origins = (
        center
        + cols.reshape(-1, 1) * frame[:, 0]
        + rows.reshape(-1, 1) * frame[:, 1]
        + CAST_HEIGHT_M * frame[:, 2]
    )
    direction = -frame[:, 2]
    depth = CAST_HEIGHT_M + float(np.ptp(mesh.vertices @ frame[:, 2])) + side_m
    smooth = trimesh.graph.smooth_shade(mesh, angle=SMOOTH_ANGLE_RAD)
    _, tri, res = MeshRaycaster(smooth).first_hit(origins, np.tile(direction, (len(origins), 1)), depth)
    hit = tri >= 0

    points = np.zeros((resolution * resolution, 3))
    normals = np.zeros((resolution * resolution, 3))
    u, v = res["u"][hit, None].astype(np.float64), res["v"][hit, None].astype(np.float64)
    weights = (1 - u - v, u, v)  # barycentric: points exactly on the hit triangle, in float64
    corners = smooth.vertices[smooth.faces[tri[hit]]]  # (n, 3 corners, 3)
    points[hit] = sum(w * corners[:, i] for i, w in enumerate(weights))
    corners = smooth.vertex_normals[smooth.faces[tri[hit]]]
    n = sum(w * corners[:, i] for i, w in enumerate(weights))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    n *= np.where(n @ direction < 0, -1.0, 1.0)[:, None]  # inward = along the casting ray
    normals[hit] = n
    shape = (resolution, resolution, 3)
    log.debug("surface map %s: %d of %d cells on the surface", group, int(hit.sum()), hit.size)
    return SurfaceMap(
        group, (points * 1e3).astype(np.float32).reshape(shape), normals.astype(np.float32).reshape(shape)
    )


def pad_grid_side(pad: PadSpec) -> float:
    """Side of the square grid window of ``pad`` (metres): the longer pad side plus the margins."""
    return max(pad.length, pad.width) * (1 + 2 * GRID_MARGIN)


def surface_map_from_pad(
    pad: PadSpec, resolution: int = NATIVE_RESOLUTION, group: str = "pad", mesh: trimesh.Trimesh | None = None
) -> SurfaceMap:
    """Surface map on the grid of a declarative pad (see ``tactile.pads``).

    ``mesh`` (attach-body frame) is what is rasterised; by default the pad's own contact sheet.
    """
    mesh = build_pad_mesh(pad) if mesh is None else mesh
    return surface_map_from_mesh(mesh, pad.center, pad.frame(), pad_grid_side(pad), resolution, group)


def _apply(matrix: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """matrix @ v for (..., 3) vectors in float64, summed in a fixed order (no BLAS): byte-stable float32."""
    m, v = np.asarray(matrix, dtype=np.float64), np.asarray(vectors, dtype=np.float64)
    out = np.empty(v.shape, dtype=np.float64)
    for i in range(3):
        out[..., i] = m[i, 0] * v[..., 0] + m[i, 1] * v[..., 1] + m[i, 2] * v[..., 2]
    return (out + 0.0).astype(np.float32)  # + 0 turns -0.0 (empty cells times -1) back into 0.0


def reflected_surface_map(surface: SurfaceMap, reflection, group: str) -> SurfaceMap:
    """The surface moved by the orthogonal ``reflection`` (points and normals alike), named ``group``.

    The left hand is the right one reflected by ``sim.embodiment.mirror.M`` (the caller passes it);
    the reflected maps keep the right hand's grid, so one pixel is the same spot of the finger on
    both sides.
    """
    reflection = np.asarray(reflection, dtype=np.float64)
    if reflection.shape != (3, 3) or not np.allclose(reflection @ reflection.T, np.eye(3), atol=1e-9):
        raise ValueError(f"reflection must be an orthogonal 3x3 matrix, got {reflection.tolist()}")
    return SurfaceMap(group, _apply(reflection, surface.point_mm), _apply(reflection, surface.normal))


def surface_map_paths(directory, group: str) -> tuple[Path, Path]:
    directory = Path(directory)
    return directory / f"{group}_point.npy", directory / f"{group}_normal.npy"


def save_surface_map(surface: SurfaceMap, directory) -> tuple[Path, Path]:
    """Write ``{group}_point.npy`` (mm) and ``{group}_normal.npy`` (inward) as float32 (H, W, 3)."""
    from episodes.atomic import atomic_path   # write-then-rename: never a half-written asset

    point_path, normal_path = surface_map_paths(directory, surface.group)
    for path, array in ((point_path, surface.point_mm), (normal_path, surface.normal)):
        with atomic_path(path) as tmp, open(tmp, "wb") as f:
            np.save(f, np.ascontiguousarray(array, dtype=np.float32), allow_pickle=False)
    return point_path, normal_path


def _load_map(path: Path, field: str) -> np.ndarray:
    if not path.is_file():
        raise TactileSpecError(path, field, "an existing .npy file")
    try:
        array = np.load(path, allow_pickle=False)
    except (OSError, ValueError, EOFError) as exc:     # not .npy, truncated, or an object array
        raise TactileSpecError(path, field, "a readable .npy array (no pickles)", str(exc)) from None
    if not isinstance(array, np.ndarray):               # an .npz archive
        raise TactileSpecError(path, field, "a single .npy array", type(array).__name__)
    if array.ndim != 3 or array.shape[2] != 3 or array.shape[0] < 1 or array.shape[1] < 1:
        raise TactileSpecError(path, field, "an array of shape (H, W, 3)", array.shape)
    if not np.issubdtype(array.dtype, np.floating):
        raise TactileSpecError(path, field, "a float array", str(array.dtype))
    if not np.all(np.isfinite(array)):
        raise TactileSpecError(path, field, "finite values only")
    return array.astype(np.float32, copy=False)


def load_surface_map(point_path, normal_path, normal_convention: str, group: str | None = None) -> SurfaceMap:
    """Load a point map (mm) and normal map; ``outward`` normals are flipped to inward."""
    if normal_convention not in ("inward", "outward"):
        raise TactileSpecError(None, "normal_convention", "'inward' or 'outward'", normal_convention)
    point_path, normal_path = Path(point_path), Path(normal_path)
    points = _load_map(point_path, "point")
    normals = _load_map(normal_path, "normal")
    if normals.shape != points.shape:
        raise TactileSpecError(normal_path, "normal", f"the point map's shape {points.shape}", normals.shape)
    norm = np.linalg.norm(normals, axis=-1)
    valid = norm > 0.5
    if np.any(valid & (np.abs(norm - 1.0) > 1e-3)):
        raise TactileSpecError(normal_path, "normal", "unit normals in valid cells (zero elsewhere)")
    if normal_convention == "outward":
        normals = -normals
    normals = np.where(valid[..., None], normals, np.float32(0)).astype(np.float32)
    points = np.where(valid[..., None], points, np.float32(0)).astype(np.float32)
    if group is None:
        group = point_path.name.removesuffix(".npy").removesuffix("_point")
    return SurfaceMap(group, points, normals)
