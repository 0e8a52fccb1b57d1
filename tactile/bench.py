"""Tactile throughput benchmark: a full grasp, a no-contact frame and an ``mj_ray`` baseline.

Scene: ``sites`` identical finger pads (30 x 18 mm, rounded with R 9 mm) at ``resolution`` cells,
spread around a 40 mm icosphere (20,480 triangles), each pressed 1 mm into it. Everything runs on
one thread, so rays per second are rays per second per core.
"""

from __future__ import annotations

import math
import platform
import time

import cv2
import mujoco
import numpy as np
import trimesh

from tactile.pads import parse_pad
from tactile.sensor import TactileSensor, TactileSite
from tactile.surface import surface_map_from_pad

OBJECT_RADIUS_M = 0.04
PRESS_DEPTH_M = 0.001
BASELINE_RAYS = 20_000
PAD = dict(center=[0, 0, 0], normal=[0, 0, 1], axis=[0, 1, 0], length=0.03, width=0.018, curvature_radius=0.009)


def _rotation_towards(direction: np.ndarray) -> np.ndarray:
    """A rotation taking +z to ``direction`` (unit)."""
    z = direction / np.linalg.norm(direction)
    helper = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def _grasp_poses(count: int, center: np.ndarray) -> dict[str, tuple]:
    """Pads on Fibonacci directions around the object, outward normals at its centre, 1 mm deep."""
    poses = {}
    for i in range(count):
        y = 1 - 2 * (i + 0.5) / count
        phi = i * math.pi * (3 - math.sqrt(5))
        u = np.array([math.sqrt(1 - y * y) * math.cos(phi), y, math.sqrt(1 - y * y) * math.sin(phi)])
        poses[f"site{i}"] = (center + u * (OBJECT_RADIUS_M - PRESS_DEPTH_M), _rotation_towards(-u))
    return poses


def _timed(fn, repeats: int) -> float:
    """Median wall time of ``fn()`` in seconds."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def _mj_ray_baseline(mesh: trimesh.Trimesh, center: np.ndarray, origins, directions, max_range: float):
    """Per-ray ``mujoco.mj_ray`` in a Python loop: (seconds, distances with misses as inf)."""
    spec = mujoco.MjSpec()
    spec.add_mesh(name="object", uservert=mesh.vertices.reshape(-1).tolist(), userface=mesh.faces.reshape(-1).tolist())
    body = spec.worldbody.add_body(name="object", pos=center.tolist())
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="object")
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    geomid = np.zeros(1, dtype=np.int32)
    out = np.empty(len(origins))
    start = time.perf_counter()
    for i in range(len(origins)):
        out[i] = mujoco.mj_ray(model, data, origins[i], directions[i], None, 1, -1, geomid)
    seconds = time.perf_counter() - start
    return seconds, np.where((out >= 0) & (out <= max_range), out, np.inf)


def run_tactile_bench(resolution: int = 240, sites: int = 10) -> dict:
    """Measure tactile sensing cost on one thread; returns JSON-able figures (prints nothing)."""
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)  # Embree and numpy already run on one thread here; keep the blur there too
    try:
        return _bench(resolution, sites)
    finally:
        cv2.setNumThreads(threads)


def _bench(resolution: int, sites: int) -> dict:
    surface = surface_map_from_pad(parse_pad(PAD, "bench"), resolution, "bench")
    object_mesh = trimesh.creation.icosphere(subdivisions=5, radius=OBJECT_RADIUS_M)
    center = np.array([0.3, -0.1, 0.9])  # world placement: rays really are moved into the object frame
    sensor = TactileSensor([TactileSite(f"site{i}", surface) for i in range(sites)], step=1)
    sensor.add_target("object", object_mesh)
    site_poses = _grasp_poses(sites, center)
    object_pose = {"object": (center, np.eye(3))}
    away_pose = {"object": (center + np.array([0, 0, 1.0]), np.eye(3))}

    frame = sensor.sense(site_poses, object_pose)
    grasp_s = _timed(lambda: sensor.sense(site_poses, object_pose), 5)
    empty = sensor.sense(site_poses, away_pose)
    empty_s = _timed(lambda: sensor.sense(site_poses, away_pose), 50)

    # Baseline: first-pass rays of site 0 in world coordinates, every k-th for a fixed budget.
    rays = sensor._rays[0]
    pos, rot = site_poses["site0"]
    origins = rays.points_m @ rot.T + pos
    directions = rays.normals @ rot.T
    pick = np.arange(0, len(origins), max(1, len(origins) // BASELINE_RAYS))[:BASELINE_RAYS]
    base_s, base_depth = _mj_ray_baseline(object_mesh, center, origins[pick], directions[pick], sensor.max_range_m)
    caster = sensor._targets["object"].raycaster
    ours_depth, _, _ = caster.first_hit(origins[pick] - center, directions[pick], sensor.max_range_m)
    both = np.isfinite(base_depth) & np.isfinite(ours_depth)
    agree = np.isfinite(base_depth) == np.isfinite(ours_depth)

    rays_per_s = frame.rays_cast / grasp_s
    base_rays_per_s = len(pick) / base_s
    return {
        "resolution": resolution,
        "sites": sites,
        "threads": 1,
        "machine": platform.processor() or platform.machine(),
        "grasp_sites_in_contact": int(np.count_nonzero(frame.mask.any(axis=(1, 2)))),
        "grasp_contact_cells": int(frame.mask.sum()),
        "grasp_rays_cast": int(frame.rays_cast),
        "grasp_frame_ms": round(grasp_s * 1e3, 2),
        "rays_per_s_per_core": round(rays_per_s),
        "no_contact_frame_ms": round(empty_s * 1e3, 3),
        "no_contact_rays_cast": int(empty.rays_cast),
        "mj_ray_rays_per_s": round(base_rays_per_s),
        "speedup_vs_mj_ray": round(rays_per_s / base_rays_per_s, 1),
        "mj_ray_note": (
            f"mj_ray baseline: Python loop over {len(pick)} first-pass rays of one site, "
            "rate extrapolated; ours counts both passes and includes transforms and encoding"
        ),
        "mj_ray_hit_agreement": round(float(agree.mean()), 4),
        "mj_ray_max_depth_diff_m": float(np.max(np.abs(base_depth[both] - ours_depth[both]), initial=0.0)),
        "goal_rays_per_s": 5_000_000,
        "goal_no_contact_ms": 2.0,
        "meets_goals": bool(rays_per_s >= 5e6 and empty_s * 1e3 < 2.0),
    }
