"""Direct embreex ray casting against one triangle mesh held in its own local frame.

The Embree scene (BVH) is built once per mesh; callers move rays into the mesh frame instead of
moving the mesh. Embree works in float32 and reports hits on either side of a triangle.
"""

from __future__ import annotations

import numpy as np
import trimesh
from embreex import rtcore_scene
from embreex.mesh_construction import TriangleMesh


class MeshRaycaster:
    """One Embree scene for one mesh (vertices in the mesh's local frame)."""

    def __init__(self, mesh: trimesh.Trimesh):
        vertices = np.ascontiguousarray(mesh.vertices, dtype=np.float32)
        faces = np.ascontiguousarray(mesh.faces, dtype=np.int32)
        if len(faces) == 0:
            raise ValueError("cannot build a ray-cast scene from a mesh without faces")
        self._scene = rtcore_scene.EmbreeScene()
        TriangleMesh(scene=self._scene, vertices=vertices, indices=faces)
        self.bounds = np.asarray(mesh.bounds, dtype=np.float64)  # (2, 3) local AABB

    def first_hit(self, origins, directions, max_range: float) -> tuple[np.ndarray, np.ndarray, dict]:
        """Nearest hit within ``max_range``: (distance float32 [N], triangle id int32 [N], raw).

        Misses have distance ``inf`` and triangle id -1; ``raw`` holds Embree's barycentric
        ``u``/``v`` for callers that interpolate vertex attributes.
        """
        o = np.ascontiguousarray(origins, dtype=np.float32)
        d = np.ascontiguousarray(directions, dtype=np.float32)
        tfar = np.full(len(o), max_range, dtype=np.float32)
        if len(o) == 0:
            return tfar, np.zeros(0, np.int32), {"u": tfar, "v": tfar}
        res = self._scene.run(o, d, dists=tfar, output=1)
        prim = res["primID"]
        dist = np.where(prim >= 0, res["tfar"], np.float32(np.inf)).astype(np.float32)
        return dist, prim, res

    def depth(self, origins, directions, max_range: float) -> np.ndarray:
        """Nearest-hit distance within ``max_range`` (float32 [N], ``inf`` on a miss).

        Uses Embree's distance-only query, the cheapest nearest-hit query embreex offers; a hit at
        exactly ``max_range`` counts as a miss.
        """
        o = np.ascontiguousarray(origins, dtype=np.float32)
        d = np.ascontiguousarray(directions, dtype=np.float32)
        if len(o) == 0:
            return np.zeros(0, dtype=np.float32)
        tfar = np.full(len(o), max_range, dtype=np.float32)
        out = np.asarray(self._scene.run(o, d, dists=tfar.copy(), query="DISTANCE"), dtype=np.float32)
        return np.where(out < tfar, out, np.float32(np.inf))

    def any_hit(self, origins, directions) -> np.ndarray:
        """Whether each ray (unbounded range) meets the mesh at all: bool [N]."""
        if len(origins) == 0:
            return np.zeros(0, dtype=bool)
        o = np.ascontiguousarray(origins, dtype=np.float32)
        d = np.ascontiguousarray(directions, dtype=np.float32)
        return self._scene.run(o, d, query="OCCLUDED") >= 0
