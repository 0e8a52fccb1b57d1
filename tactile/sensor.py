"""Per-frame tactile sensing: surface-aligned ray casting against task-object meshes.

For every site, rays start at the valid surface points (mm -> m, moved to the world by the site's
attach-body pose) and run along the inward normals for at most ``max_range_m`` (15 mm) against the
registered targets (task objects and articulated links; the caller never registers the robot or
the table). Contact-consistency check, two passes (paper appendix "Signal Semantics and Depth
Quantization"): after the first hit, the origin is advanced to just short of the hit and a reverse
ray is cast outward against the same target; the sample is kept only if that reverse ray also hits,
which holds once the object surface has crossed the nominal surface origin. An object lying behind
the pad (inside the finger's range but not pressed through the surface) therefore gives nothing.

Each target's Embree scene is built once in its local frame; every frame the candidate rays are
moved into that frame instead. A broad phase (``tactile.broadphase``) skips site-target pairs that
cannot meet.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import trimesh

from tactile.broadphase import LocalBox, aabb_overlaps, boxes_overlap, ray_volume_box, world_aabbs
from tactile.quantize import encode_tacmap
from tactile.raycast import MeshRaycaster
from tactile.surface import SurfaceMap

log = logging.getLogger(__name__)

MAX_RANGE_M = 0.015
PASS2_BACKOFF_M = 1e-5  # "just short of the hit": reverse-ray origin this far before the first hit

Pose = tuple  # (pos float[3], rot float[3, 3]) in the world


@dataclass(frozen=True)
class TactileSite:
    """A named tactile site: its surface map lives in the frame of ``attach_body``."""

    name: str
    surface: SurfaceMap
    attach_body: str | None = None


@dataclass(frozen=True, eq=False)
class TactileFrame:
    site_names: tuple[str, ...]
    tacmap: np.ndarray  # uint8 [S, H, W], encoded and smoothed
    distance_m: np.ndarray  # float32 [S, H, W], first-hit depth, zero where invalid
    mask: np.ndarray  # bool [S, H, W], contact-validity mask
    rays_cast: int  # both passes, for cost accounting


@dataclass(frozen=True)
class _SiteRays:
    cells: np.ndarray  # flat indices of valid cells in the (H, W) grid
    points_m: np.ndarray  # float64 [N, 3], attach-body frame
    normals: np.ndarray  # float64 [N, 3], unit inward
    box: LocalBox
    points_t: np.ndarray  # float32 [3, N], the same points stored by coordinate
    normals_t: np.ndarray  # float32 [3, N]


def _transform(rot: np.ndarray, vectors_t: np.ndarray, shift: np.ndarray | None = None) -> np.ndarray:
    """rot @ v (+ shift) for float32 [3, N] vectors -> contiguous float32 [N, 3] ray arrays.

    Plain element-wise float32 arithmetic (no BLAS), so results do not depend on the CPU's BLAS
    kernels; float32 is what Embree consumes anyway.
    """
    rot = rot.astype(np.float32)
    out = np.empty((vectors_t.shape[1], 3), dtype=np.float32)
    for i in range(3):
        row = rot[i, 0] * vectors_t[0] + rot[i, 1] * vectors_t[1] + rot[i, 2] * vectors_t[2]
        if shift is not None:
            row += np.float32(shift[i])
        out[:, i] = row
    return out


@dataclass(frozen=True)
class _Target:
    raycaster: MeshRaycaster
    box: LocalBox


class TactileSensor:
    def __init__(self, sites: list[TactileSite], step: int = 1, max_range_m: float = MAX_RANGE_M):
        if not sites:
            raise ValueError("TactileSensor needs at least one site")
        names = [s.name for s in sites]
        if len(set(names)) != len(names):
            raise ValueError(f"site names must be unique, got {names}")
        self.step = int(step)
        self.max_range_m = float(max_range_m)
        self.site_names = tuple(names)
        shapes = {s.name: s.surface.subsample(self.step).shape for s in sites}
        self.shape = shapes[names[0]]
        if any(shape != self.shape for shape in shapes.values()):
            raise ValueError(f"all sites need surface maps of one shape at step {step}, got {shapes}")
        by_surface: dict[int, _SiteRays] = {}  # sites of one group share one surface map
        self._rays = []
        for site in sites:
            key = id(site.surface)
            if key not in by_surface:
                by_surface[key] = self._site_rays(site.surface.subsample(self.step))
            self._rays.append(by_surface[key])
        self._targets: dict[str, _Target] = {}

    def _site_rays(self, surface: SurfaceMap) -> _SiteRays:
        valid = surface.valid.reshape(-1)
        cells = np.flatnonzero(valid)
        points = surface.point_mm.reshape(-1, 3)[cells].astype(np.float64) * 1e-3
        normals = surface.normal.reshape(-1, 3)[cells].astype(np.float64)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        box = ray_volume_box(points, normals, self.max_range_m)
        by_coordinate = [np.ascontiguousarray(a.T, dtype=np.float32) for a in (points, normals)]
        return _SiteRays(cells, points, normals, box, *by_coordinate)

    def add_target(self, name: str, mesh_local: trimesh.Trimesh | MeshRaycaster) -> None:
        """Register a target (task object or link) in its own local frame: a mesh, whose BVH is built
        here once, or a ``MeshRaycaster`` already built (and possibly shared: it is read-only)."""
        if name in self._targets:
            raise ValueError(f"target '{name}' is already registered")
        caster = mesh_local if isinstance(mesh_local, MeshRaycaster) else MeshRaycaster(mesh_local)
        self._targets[name] = _Target(caster, LocalBox.around(caster.bounds))

    @property
    def target_names(self) -> tuple[str, ...]:
        return tuple(self._targets)

    def _check_poses(self, site_poses: dict, target_poses: dict) -> None:
        missing = [n for n in self.site_names if n not in site_poses]
        missing += [n for n in self._targets if n not in target_poses]
        if missing:
            raise KeyError(f"no pose given for {missing}")

    def candidate_pairs(self, site_poses: dict, target_poses: dict) -> list[tuple[str, str]]:
        """(site, target) pairs whose boxes overlap: the only pairs ``sense`` ray casts."""
        self._check_poses(site_poses, target_poses)
        targets = list(self._targets)
        target_boxes = [self._targets[n].box.in_world(*target_poses[n]) for n in targets]
        site_boxes = [rays.box.in_world(*site_poses[n]) for n, rays in zip(self.site_names, self._rays)]
        near = aabb_overlaps(world_aabbs(site_boxes), world_aabbs(target_boxes))
        return [(self.site_names[s], targets[t]) for s, t in zip(*np.nonzero(near))
                if boxes_overlap(site_boxes[s], target_boxes[t])]

    def sense(self, site_poses: dict, target_poses: dict) -> TactileFrame:
        """One frame: ``site_poses[name]`` and ``target_poses[name]`` are world (pos[3], rot[3, 3])."""
        pairs = self.candidate_pairs(site_poses, target_poses)
        s_count, (h, w) = len(self.site_names), self.shape
        distance = np.zeros((s_count, h * w), dtype=np.float32)
        mask = np.zeros((s_count, h * w), dtype=bool)
        tacmap = np.zeros((s_count, h, w), dtype=np.uint8)
        rays_cast = 0
        for s, (name, rays) in enumerate(zip(self.site_names, self._rays)):
            targets = [t for site, t in pairs if site == name]
            if not targets:
                continue
            depth, valid, cast = self._cast_site(rays, site_poses[name], targets, target_poses)
            rays_cast += cast
            distance[s, rays.cells[valid]] = depth[valid]
            mask[s, rays.cells[valid]] = True
            if valid.any():
                tacmap[s] = encode_tacmap(distance[s].reshape(h, w), mask[s].reshape(h, w), self.step)
        shape = (s_count, h, w)
        return TactileFrame(self.site_names, tacmap, distance.reshape(shape), mask.reshape(shape), rays_cast)

    def _cast_site(self, rays: _SiteRays, site_pose, targets: list[str], target_poses: dict):
        """Both passes for one site: (depth float32 [N], valid bool [N], rays cast)."""
        best = np.full(len(rays.cells), np.inf, dtype=np.float32)
        winner = np.full(len(rays.cells), -1, dtype=np.int32)
        local_rays = []
        site_pos, site_rot = (np.asarray(a, dtype=np.float64) for a in site_pose)
        for k, name in enumerate(targets):
            pos, rot = (np.asarray(a, dtype=np.float64) for a in target_poses[name])
            to_local = rot.T @ site_rot  # attach-body frame -> target frame
            origins = _transform(to_local, rays.points_t, rot.T @ (site_pos - pos))
            directions = _transform(to_local, rays.normals_t)
            depth = self._targets[name].raycaster.depth(origins, directions, self.max_range_m)
            closer = depth < best
            best[closer], winner[closer] = depth[closer], k
            local_rays.append((origins, directions))
        cast = len(targets) * len(rays.cells)
        valid = np.zeros(len(rays.cells), dtype=bool)
        for k, name in enumerate(targets):  # pass 2: reverse ray from just short of the first hit
            sel = np.flatnonzero(winner == k)
            if len(sel) == 0:
                continue
            origins, directions = local_rays[k][0][sel], local_rays[k][1][sel]
            start = origins + (best[sel] - np.float32(PASS2_BACKOFF_M))[:, None] * directions
            valid[sel] = self._targets[name].raycaster.any_hit(start, -directions)
            cast += len(sel)
        return np.where(valid, best, np.float32(0)), valid, cast
