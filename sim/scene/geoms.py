"""Parts as MuJoCo geoms: one geom per part, the body's mass shared over them by volume. A mesh
part brings its convex hull as a mesh asset of the same name (see mesh_files)."""

from __future__ import annotations

import mujoco

from sim.scene.mesh_files import load_hull
from sim.scene.parts import GEOM_TYPES, Part, pad_size, part_masses


def add_part_geoms(spec: mujoco.MjSpec, body: mujoco.MjsBody, names: list[str], parts: tuple[Part, ...],
                   total_mass: float, friction: list[float], rgba, contact: dict) -> None:
    """Geoms ``names`` (one per part) on ``body``; a part without its own colour takes ``rgba``."""
    for name, part, mass in zip(names, parts, part_masses(parts, total_mass), strict=True):
        shape = {"size": pad_size(part.size)}
        if part.mesh is not None:
            hull = load_hull(part.mesh)
            spec.add_mesh(name=name, uservert=hull.vertices.ravel().tolist(), userface=hull.faces.ravel().tolist())
            shape = {"meshname": name}
        body.add_geom(name=name, type=GEOM_TYPES[part.shape], pos=list(part.pos), quat=list(part.quat), mass=mass,
                      friction=list(friction), rgba=list(part.rgba or rgba), **shape, **contact)
