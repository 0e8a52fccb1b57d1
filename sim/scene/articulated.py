"""Articulated objects: links on hinge or slide joints, declared in the task file.

    fridge:
      base: fixed
      parts: [...]
      links:
        left_door:                      # joint "fridge/left_door" for the evaluator
          pos: [-0.2, -0.18, 0.0]       # joint anchor = link frame, in the object frame
          joint: {type: hinge, axis: [0, 0, 1], range: [-1.9, 0], damping: 0.4, frictionloss: 0.05}
          parts: [{shape: box, size: [0.1, 0.01, 0.25], pos: [0.1, -0.01, 0]}]
          mass: 0.6
      key_rows:                         # a row of identical keys: piano, keyboard, mouse buttons
        - names: [C3, D3, E3]
          origin: [-0.2, 0.0, 0.03]     # first key's link frame
          pitch: [0.024, 0, 0]          # from one key to the next
          parts: [{shape: box, size: [0.011, 0.07, 0.008]}]
          joint: {type: slide, axis: [0, 0, 1], range: [-0.012, 0], stiffness: 60, springref: 0.005}
          mass: 0.02

Doors, lids, monitor hinges and faucet handles are hinge links; keys are slide (or hinge) links
with a spring: `stiffness` pulls the joint towards `springref`, and a `springref` beyond the range
preloads the key against its rest limit so gravity cannot push it down. `initial` is the joint
value at the start of an episode (a lid left ajar, a monitor turned aside).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from sim.schema.object_parts import LinkBody
from sim.schema.task import TaskObject
from sim.scene.geoms import add_part_geoms
from sim.scene.parts import Part, build_parts, euler_quat

JOINT_TYPES = {"hinge": mujoco.mjtJoint.mjJNT_HINGE, "slide": mujoco.mjtJoint.mjJNT_SLIDE}
LIMIT_SOLREF = [0.004, 1.0]   # stiff stops: a preloaded key rests within ~0.1 mm of its limit


@dataclass(frozen=True)
class JointSpec:
    type: str
    axis: tuple[float, float, float]
    range: tuple[float, float]
    damping: float
    stiffness: float
    springref: float
    frictionloss: float
    armature: float
    initial: float


@dataclass(frozen=True)
class LinkSpec:
    name: str                                 # joint and link "object/name"
    pos: tuple[float, float, float]           # link frame (joint anchor) in the object frame
    quat: tuple[float, float, float, float]
    joint: JointSpec
    parts: tuple[Part, ...]                   # in the link frame
    mass: float
    rgba: tuple[float, float, float, float] | None


def _link(path, field: str, name: str, body: LinkBody, pos) -> LinkSpec:
    """A link (or one key of a row) from its checked schema; ``path`` and ``field`` name a mesh part's
    file that cannot be read."""
    j = body.joint
    axis = np.asarray(j.axis, float)
    joint = JointSpec(type=j.type, axis=tuple((axis / np.linalg.norm(axis)).tolist()),
                      range=(float(j.range[0]), float(j.range[1])), damping=j.damping, stiffness=j.stiffness,
                      springref=j.springref, frictionloss=j.frictionloss, armature=j.armature, initial=j.initial)
    parts, _ = build_parts(path, f"{field}.parts", body.parts)
    return LinkSpec(name=name, pos=tuple(float(v) for v in pos), quat=euler_quat(body.euler_deg), joint=joint,
                    parts=parts, mass=body.mass,
                    rgba=tuple(float(v) for v in body.rgba) if body.rgba is not None else None)


def build_links(path, field: str, obj: TaskObject) -> tuple[LinkSpec, ...]:
    """An object's `links` and `key_rows` (checked by their schema), in declaration order (links first)."""
    links = [_link(path, f"{field}.links.{name}", name, body, body.pos) for name, body in (obj.links or {}).items()]
    for i, row in enumerate(obj.key_rows or []):
        origin, pitch = np.asarray(row.origin, float), np.asarray(row.pitch, float)
        for k, key in enumerate(row.names):
            links.append(_link(path, f"{field}.key_rows[{i}]", key, row, (origin + k * pitch).round(6).tolist()))
    return tuple(links)


def add_links(spec: mujoco.MjSpec, body: mujoco.MjsBody, object_name: str, links, friction: float,
              rgba, contact: dict) -> None:
    """Child bodies of the object's body, one joint each, named "<object>/<link>". Links never
    collide with their own object's base: MuJoCo filters parent-child contacts only below a free
    body, not for a base fixed in the world."""
    # MjSpec reads hinge angles in the compiler's unit (degrees by default); task files use radians
    unit = 180.0 / np.pi if spec.compiler.degree else 1.0
    for link in links:
        name = f"{object_name}/{link.name}"
        child = body.add_body(name=name, pos=list(link.pos), quat=list(link.quat))
        j = link.joint
        scale = unit if j.type == "hinge" else 1.0
        child.add_joint(name=name, type=JOINT_TYPES[j.type], axis=list(j.axis),
                        range=[j.range[0] * scale, j.range[1] * scale], damping=j.damping,
                        stiffness=j.stiffness, springref=j.springref * scale, frictionloss=j.frictionloss,
                        armature=j.armature, solref_limit=LIMIT_SOLREF)
        spec.add_exclude(bodyname1=object_name, bodyname2=name)
        add_part_geoms(spec, child, [f"{name}/{k}" for k in range(len(link.parts))], link.parts, link.mass,
                       [friction, 0.01, 0.0], link.rgba or rgba, contact)

