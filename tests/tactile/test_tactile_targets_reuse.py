"""Sphere and ellipsoid targets start from one unit icosphere per level per process: the meshes (hence
the ray-cast scenes and every tactile byte) are those of a fresh ``trimesh.creation.icosphere``."""

import mujoco
import numpy as np
import trimesh

from sim.unit_shapes import unit_icosphere
from tactile.targets import _sphere_subdivisions, clear_cache, primitive_mesh

SPHERE, ELLIPSOID = mujoco.mjtGeom.mjGEOM_SPHERE, mujoco.mjtGeom.mjGEOM_ELLIPSOID


def fresh(radii) -> trimesh.Trimesh:
    """The mesh as built before the reuse: a new icosphere at the chosen level, scaled."""
    radii = np.asarray(radii, dtype=np.float64)
    mesh = trimesh.creation.icosphere(subdivisions=_sphere_subdivisions(float(radii.max())), radius=1.0)
    mesh.apply_scale(radii)
    return mesh


def same_bytes(a: trimesh.Trimesh, b: trimesh.Trimesh) -> bool:
    return (np.asarray(a.vertices).tobytes() == np.asarray(b.vertices).tobytes()
            and np.asarray(a.faces).tobytes() == np.asarray(b.faces).tobytes()
            and np.asarray(a.bounds).tobytes() == np.asarray(b.bounds).tobytes())


def test_spheres_and_ellipsoids_match_a_fresh_icosphere_byte_for_byte():
    clear_cache()
    cases = [(SPHERE, (0.036, 0, 0), (0.036,) * 3), (ELLIPSOID, (0.027, 0.034, 0.027), (0.027, 0.034, 0.027)),
             (SPHERE, (0.004, 0, 0), (0.004,) * 3), (SPHERE, (0.036, 0, 0), (0.036,) * 3)]
    for gtype, size, radii in cases:          # the last repeats the first: built from the cache this time
        assert same_bytes(primitive_mesh(gtype, size), fresh(radii))


def test_a_target_mesh_is_a_copy_that_leaves_the_shared_unit_sphere_alone():
    clear_cache()
    level = _sphere_subdivisions(0.036)
    before = np.asarray(unit_icosphere(level).vertices).copy()
    mesh = primitive_mesh(SPHERE, (0.036, 0, 0))
    mesh.vertices += 1.0                      # a caller changing its mesh
    assert np.array_equal(np.asarray(unit_icosphere(level).vertices), before)
    assert np.allclose(np.linalg.norm(before, axis=1), 1.0)
    assert same_bytes(primitive_mesh(SPHERE, (0.036, 0, 0)), fresh((0.036,) * 3))
