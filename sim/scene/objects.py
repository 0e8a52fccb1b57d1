"""Task objects as MuJoCo bodies: a base body (free, or fixed in the world) carrying the object's
parts (primitives and mesh hulls), plus its articulated links. The tactile layer ray-casts against
these geoms (`tactile.targets`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from sim.scene.articulated import add_links
from sim.scene.geoms import add_part_geoms
from sim.scene.parts import Part

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
    add_part_geoms(spec, body, [name], (Part(shape, tuple(size)),), mass, [friction, 0.01, rolling_friction], rgba,
                   _contact(rolling_friction))


def add_task_object(spec: mujoco.MjSpec, obj: ObjectSpec, pos, quat) -> None:
    """The object's body at pos/quat: a free joint unless its base is fixed, one geom per part and
    its links. A one-part object's geom carries the object's name."""
    body = spec.worldbody.add_body(name=obj.name, pos=list(pos), quat=list(quat))
    if obj.base == "free":
        body.add_freejoint(name=f"{obj.name}_free")
    names = [obj.name] if len(obj.parts) == 1 else [f"{obj.name}/{k}" for k in range(len(obj.parts))]
    add_part_geoms(spec, body, names, obj.parts, obj.mass, [obj.friction, 0.01, obj.rolling_friction], obj.rgba,
                   _contact(obj.rolling_friction))
    add_links(spec, body, obj.name, obj.links, obj.friction, obj.rgba, {"condim": 4, "solref": OBJECT_SOLREF})
