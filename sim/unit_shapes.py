"""Unit meshes built once per process and shared: 2D-box labels sample the surfaces of spheres and
ellipsoids, tactile casts rays at them. Callers scale a copy, never the shared mesh."""

from __future__ import annotations

import functools

import trimesh


@functools.lru_cache(maxsize=None)
def unit_icosphere(level: int) -> trimesh.Trimesh:
    """The unit icosphere of subdivision ``level`` (~14 ms to build at level 2, more above)."""
    return trimesh.creation.icosphere(subdivisions=level, radius=1.0)
