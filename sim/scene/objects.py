"""Task objects as MuJoCo bodies: a base body (free, or fixed in the world) carrying the object's
primitive parts, plus its articulated links. The tactile layer ray-casts against these geoms
(`tactile.targets`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from sim.scene.articulated import add_links
from sim.scene.parts import GEOM_TYPES, pad_size, part_masses

if TYPE_CHECKING:
    from sim.tasks import ObjectSpec

OBJECT_SOLREF = [0.004, 1.0]


def yaw_quat(yaw_deg: float) -> list[float]:
    half = np.deg2rad(yaw_deg) / 2
    return [float(np.cos(half)), 0.0, 0.0, float(np.sin(half))]


def _contact(rolling_friction: float) -> dict:
    # condim 6 adds rolling resistance; without it a sphere rolls on forever on a flat plate
    return {"condim": 6 if rolling_friction > 0 else 4, "solref": OBJECT_SOLREF}


def add_free_object(spec: mujoco.MjSpec, name: str, shape: str, size, mass: float, friction: float,
                    rgba, pos, quat, rolling_friction: float = 0.0) -> None:
    """A one-primitive free body (distractors)."""
    body = spec.worldbody.add_body(name=name, pos=list(pos), quat=list(quat))
    body.add_freejoint(name=f"{name}_free")
    body.add_geom(name=name, type=GEOM_TYPES[shape], size=pad_size(size), mass=mass,
                  friction=[friction, 0.01, rolling_friction], rgba=list(rgba), **_contact(rolling_friction))


def add_task_object(spec: mujoco.MjSpec, obj: ObjectSpec, pos, quat) -> None:
    """The object's body at pos/quat: a free joint unless its base is fixed, one geom per part
    (mass shared by volume) and its links. A one-part object's geom carries the object's name."""
    body = spec.worldbody.add_body(name=obj.name, pos=list(pos), quat=list(quat))
    if obj.base == "free":
        body.add_freejoint(name=f"{obj.name}_free")
    contact = _contact(obj.rolling_friction)
    single = len(obj.parts) == 1
    for k, (part, mass) in enumerate(zip(obj.parts, part_masses(obj.parts, obj.mass))):
        body.add_geom(name=obj.name if single else f"{obj.name}/{k}", type=GEOM_TYPES[part.shape],
                      size=pad_size(part.size), pos=list(part.pos), quat=list(part.quat), mass=mass,
                      friction=[obj.friction, 0.01, obj.rolling_friction], rgba=list(part.rgba or obj.rgba),
                      **contact)
    add_links(spec, body, obj.name, obj.links, obj.friction, obj.rgba, {"condim": 4, "solref": OBJECT_SOLREF})
