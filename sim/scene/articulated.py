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

from sim.errors import SpecError
from sim.scene.fields import MASS_RANGE_KG, num_list, number
from sim.scene.geoms import add_part_geoms
from sim.scene.parts import Part, euler_quat, parse_parts

JOINT_TYPES = {"hinge": mujoco.mjtJoint.mjJNT_HINGE, "slide": mujoco.mjtJoint.mjJNT_SLIDE}
JOINT_KEYS = ("type", "axis", "range", "damping", "stiffness", "springref", "frictionloss", "armature", "initial")
LINK_KEYS = ("pos", "euler_deg", "joint", "parts", "mass", "rgba")
KEY_ROW_KEYS = ("names", "origin", "pitch", "euler_deg", "joint", "parts", "mass", "rgba")
DEFAULT_ARMATURE = 1e-4   # a little rotor inertia keeps light links stable at the 2 ms step
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


def parse_joint(path, field: str, raw) -> JointSpec:
    if not isinstance(raw, dict):
        raise SpecError(path, field, f"a mapping with keys {list(JOINT_KEYS)}", raw)
    for key in raw:
        if key not in JOINT_KEYS:
            raise SpecError(path, f"{field}.{key}", f"a joint key {list(JOINT_KEYS)}")
    kind = raw.get("type")
    if kind not in JOINT_TYPES:
        raise SpecError(path, f"{field}.type", f"one of {sorted(JOINT_TYPES)}", kind)
    axis = np.asarray(num_list(path, f"{field}.axis", raw.get("axis"), 3))
    if not np.linalg.norm(axis) > 0:
        raise SpecError(path, f"{field}.axis", "a non-zero axis", raw.get("axis"))
    lo, hi = num_list(path, f"{field}.range", raw.get("range"), 2)
    if not lo < hi:
        raise SpecError(path, f"{field}.range", "[low, high] with low < high", raw.get("range"))

    def value(key: str, default: float, low: float | None = 0.0) -> float:
        return number(path, f"{field}.{key}", raw.get(key, default), low)

    initial = value("initial", 0.0, low=None)
    if not lo <= initial <= hi:
        raise SpecError(path, f"{field}.initial", f"a value within the range [{lo}, {hi}]", initial)
    return JointSpec(
        type=kind, axis=tuple((axis / np.linalg.norm(axis)).tolist()), range=(lo, hi),
        damping=value("damping", 0.1), stiffness=value("stiffness", 0.0), springref=value("springref", 0.0, low=None),
        frictionloss=value("frictionloss", 0.0), armature=value("armature", DEFAULT_ARMATURE), initial=initial)


def _link(path, field, name, raw, pos, keys) -> LinkSpec:
    for key in raw:
        if key not in keys:
            raise SpecError(path, f"{field}.{key}", f"a key of {list(keys)}")
    if "joint" not in raw:
        raise SpecError(path, f"{field}.joint", "a joint {type, axis, range, ...}")
    parts, _ = parse_parts(path, f"{field}.parts", raw.get("parts"))
    mass = number(path, f"{field}.mass", raw.get("mass"), *MASS_RANGE_KG, unit="kg")
    return LinkSpec(name=name, pos=pos, quat=euler_quat(num_list(path, f"{field}.euler_deg",
                                                                 raw.get("euler_deg", [0, 0, 0]), 3)),
                    joint=parse_joint(path, f"{field}.joint", raw["joint"]), parts=parts, mass=mass,
                    rgba=num_list(path, f"{field}.rgba", raw["rgba"], 4) if "rgba" in raw else None)


def parse_links(path, field: str, raw: dict) -> tuple[LinkSpec, ...]:
    """An object's `links` mapping and `key_rows` list, in declaration order (links first)."""
    links: list[LinkSpec] = []
    declared = raw.get("links") or {}
    if not isinstance(declared, dict):
        raise SpecError(path, f"{field}.links", "a mapping of link name -> link", declared)
    for name, body in declared.items():
        where = f"{field}.links.{name}"
        if not isinstance(body, dict):
            raise SpecError(path, where, "a mapping", body)
        links.append(_link(path, where, str(name), body, num_list(path, f"{where}.pos", body.get("pos", [0, 0, 0]), 3),
                           LINK_KEYS))
    rows = raw.get("key_rows") or []
    if not isinstance(rows, list):
        raise SpecError(path, f"{field}.key_rows", "a list of key rows", rows)
    for i, row in enumerate(rows):
        where = f"{field}.key_rows[{i}]"
        if not isinstance(row, dict):
            raise SpecError(path, where, "a mapping", row)
        names = row.get("names")
        if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
            raise SpecError(path, f"{where}.names", "a non-empty list of key names", names)
        origin = np.asarray(num_list(path, f"{where}.origin", row.get("origin"), 3))
        pitch = np.asarray(num_list(path, f"{where}.pitch", row.get("pitch", [0, 0, 0]), 3))
        body = {k: v for k, v in row.items() if k not in ("names", "origin", "pitch")}
        for k, key in enumerate(names):
            pos = tuple((origin + k * pitch).round(6).tolist())
            links.append(_link(path, where, key, body, pos, KEY_ROW_KEYS))
    seen: set[str] = set()
    for link in links:
        if link.name in seen or "/" in link.name:
            raise SpecError(path, f"{field}.links", "unique link and key names without '/'", link.name)
        seen.add(link.name)
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

