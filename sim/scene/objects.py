"""Task objects as MuJoCo bodies and as meshes for tactile ray casting.

Physics uses MuJoCo primitives (robust contacts); tactile rays hit a trimesh of the same primitive
built finely enough that faceting stays well below the tactile depth resolution.
"""

from __future__ import annotations

import mujoco
import numpy as np
import trimesh

GEOM_TYPES = {
    "box": mujoco.mjtGeom.mjGEOM_BOX, "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
    "sphere": mujoco.mjtGeom.mjGEOM_SPHERE, "ellipsoid": mujoco.mjtGeom.mjGEOM_ELLIPSOID,
    "capsule": mujoco.mjtGeom.mjGEOM_CAPSULE,
}


def yaw_quat(yaw_deg: float) -> list[float]:
    half = np.deg2rad(yaw_deg) / 2
    return [float(np.cos(half)), 0.0, 0.0, float(np.sin(half))]


def add_free_object(spec: mujoco.MjSpec, name: str, shape: str, size, mass: float, friction: float,
                    rgba, pos, quat, rolling_friction: float = 0.0) -> None:
    body = spec.worldbody.add_body(name=name, pos=list(pos), quat=list(quat))
    body.add_freejoint(name=f"{name}_free")
    # condim 6 adds rolling resistance; without it a sphere rolls on forever on a flat plate
    body.add_geom(name=name, type=GEOM_TYPES[shape], size=_pad_size(size), mass=mass,
                  friction=[friction, 0.01, rolling_friction], rgba=list(rgba),
                  condim=6 if rolling_friction > 0 else 4, solref=[0.004, 1.0])


def _pad_size(size) -> list[float]:
    return [float(v) for v in size] + [0.0] * (3 - len(size))


def resting_height(shape: str, size) -> float:
    """Half-height of the object above its support when upright."""
    return {"box": size[-1] if len(size) == 3 else 0, "cylinder": size[-1], "sphere": size[0],
            "ellipsoid": size[-1], "capsule": size[-1] + size[0]}[shape]


def object_mesh(shape: str, size) -> trimesh.Trimesh:
    """A watertight mesh of the primitive in the object's local frame (MuJoCo conventions:
    cylinders and capsules along z, sizes are half-lengths)."""
    if shape == "box":
        return trimesh.creation.box(extents=2 * np.asarray(size[:3]))
    if shape == "sphere":
        return trimesh.creation.icosphere(subdivisions=4, radius=size[0])
    if shape == "ellipsoid":
        mesh = trimesh.creation.icosphere(subdivisions=4, radius=1.0)
        mesh.apply_scale(np.asarray(size[:3]))
        return mesh
    if shape == "cylinder":
        return trimesh.creation.cylinder(radius=size[0], height=2 * size[1], sections=96)
    if shape == "capsule":
        return trimesh.creation.capsule(radius=size[0], height=2 * size[1], count=[48, 48])
    raise ValueError(f"no mesh for shape '{shape}'")
