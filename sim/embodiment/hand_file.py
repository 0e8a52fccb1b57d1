"""Hand files (``sim/catalog/hands/<name>.yaml``): palm, fingers, actuators and couplings, tactile pads.

Hands are described for the RIGHT side. Hand base = flange frame; +z along the extended fingers, +y the
palm normal (the side fingers curl toward), +x lateral (thumb on -x for a right hand). The left hand is
mirrored from it (see ``mirror.py``)."""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from sim.schema.hand import HandFile
from sim.schema.robot_parts import Geom

from .catalog_paths import file_names, read_file, resolve
from .fields import _Ctx
from .frames import Transform, frame_transform
from .links import NO_GEOM_DEFAULTS, NO_JOINT_DEFAULTS, JointSpec, LinkSpec, build_geom, build_inertial, build_joint, \
    contact_excludes
from .real_model_file import parse_real_model
from .tactile_block import TactileSpec, hand_tactile


@dataclass(frozen=True)
class ActuatorSpec:
    name: str
    joint: str
    effort: float
    velocity: float
    kp: float | None = None
    kv: float | None = None


@dataclass(frozen=True)
class CouplingSpec:
    joint: str       # follower (mimic) joint
    master: str
    polycoef: tuple[float, ...]   # q_joint = c0 + c1 q_master + c2 q_master^2 + ...


def coupled_position(polycoef, master):
    """A coupled joint's position for its master's: ``polycoef`` [..., K] (constant first; rows for
    several followers), ``master`` broadcasting against it; summed from the constant term up."""
    coef, x = np.asarray(polycoef, float), np.asarray(master, float)
    value = np.zeros(np.broadcast_shapes(coef.shape[:-1], x.shape))
    for k in range(coef.shape[-1]):
        value = value + coef[..., k] * x ** k
    return value


def coupled_slope(polycoef, master):
    """d(coupled_position)/d(master), summed the same way."""
    coef, x = np.asarray(polycoef, float), np.asarray(master, float)
    slope = np.zeros(np.broadcast_shapes(coef.shape[:-1], x.shape))
    for k in range(1, coef.shape[-1]):
        slope = slope + k * coef[..., k] * x ** (k - 1)
    return slope



@dataclass(frozen=True)
class GraspProbe:
    """A cylinder the hand must be able to hold (used by the tests, hand frame)."""

    radius: float
    half_length: float
    mass: float
    pos: np.ndarray
    axis: np.ndarray
    close: dict[str, float]     # actuator -> closing target


@dataclass(frozen=True)
class TabletopGrasp:
    """How the scripted operator grasps an object resting on the table with the palm down."""

    centre: np.ndarray          # object centre in the wrist-site frame (x lateral, y palm normal, z fingers)
    close: dict[str, float]     # actuator -> closing target
    late: tuple[str, ...]       # actuators that close only after the others have formed a wall
    thin_close: dict[str, float] = field(default_factory=dict)   # a pick's thin_grasp: these targets instead


@dataclass(frozen=True)
class RoundPinch:
    """A pick's `round_pinch` (a thin round object lying on the table): a flat pinch of the thumb against
    ``fingers``, the other fingers folded ``fold`` of the way to their closed end (None: the hand's own)."""

    fingers: tuple[str, ...] | None = None
    fold: float | None = None
    tips_height_m: float | None = None     # the closed tips this high over the object's bottom (None: pressed down)


@dataclass(frozen=True)
class HandDescription:
    name: str
    display_name: str
    source: str
    assumptions: str
    mount: Transform               # hand base in the flange frame
    links: tuple[LinkSpec, ...]    # palm first
    actuators: tuple[ActuatorSpec, ...]
    couplings: tuple[CouplingSpec, ...]
    wrist_site: Transform
    tactile: TactileSpec
    home: dict[str, float]         # joint -> open-hand angle (missing joints: 0 clipped to range)
    fingers: tuple[str, ...]
    grasp_probe: GraspProbe | None
    tabletop_grasp: TabletopGrasp | None
    contact_exclude: tuple[tuple[str, str], ...]
    servo_error_at_full_effort: float
    path: Path
    real_model: Any = None         # real_model.RealModelSpec: optional real MJCF for this hand
    heavy_side_hold: str = "edge"  # a heavy object taken from the side held by its end edge, or round its body
    round_pinch: RoundPinch | None = None   # a pick's round_pinch: this flat pinch (else the step's grasp)

    @property
    def joints(self) -> list[JointSpec]:
        return [j for link in self.links for j in link.joints]

    @property
    def mass(self) -> float:
        return sum(link.inertial.mass for link in self.links)

    def joint(self, name: str) -> JointSpec:
        for j in self.joints:
            if j.name == name:
                return j
        raise KeyError(name)



def hand_names() -> list[str]:
    return file_names("hand")


def _hand_links(m: HandFile, ctx: _Ctx) -> tuple[list[LinkSpec], list[str]]:
    jdefaults = m.joint_defaults or NO_JOINT_DEFAULTS
    gdefaults = m.geom_defaults or NO_GEOM_DEFAULTS
    pgeoms = tuple(build_geom(g, gdefaults) for g in m.palm.geoms)
    palm_link = LinkSpec(name=m.palm.name, parent=None, origin=Transform.identity(), joints=(),
                         geoms=pgeoms, inertial=build_inertial(m.palm, pgeoms))
    links = [palm_link]
    fingers = []
    by_name = {palm_link.name: palm_link}
    for fi, finger in enumerate(m.fingers):
        fctx = ctx.sub(f"fingers[{fi}]")
        fingers.append(finger.name)
        parent = finger.parent if finger.parent is not None else palm_link.name
        prev_len = None
        for li, link in enumerate(finger.links):
            lctx = fctx.sub(f"links[{li}]")
            if link.name in by_name:
                lctx.sub("name").fail(f"duplicate link name {link.name!r}")
            if parent not in by_name:
                lctx.fail(f"parent link {parent!r} is not defined before it")
            origin = frame_transform(link.origin)
            if link.origin is None or link.origin.xyz is None:     # at the end of the previous link
                if prev_len is None:
                    lctx.sub("origin").fail("the first link of a finger needs origin.xyz on its parent")
                origin = Transform(np.array([0, 0, prev_len]), origin.rot)
            joints = tuple(build_joint(j, jdefaults) for j in link.joints)
            geoms = [build_geom(g, gdefaults) for g in link.geoms]
            if link.radius is not None and link.length > 0:
                # default phalanx: a capsule along +z from the joint to the next joint
                capsule = Geom(type="capsule", fromto=[0.0, 0.0, 0.0, 0.0, 0.0, link.length], radius=link.radius)
                geoms.insert(0, build_geom(capsule, gdefaults))
            geoms_t = tuple(geoms)
            spec = LinkSpec(name=link.name, parent=parent, origin=origin, joints=joints, geoms=geoms_t,
                            inertial=build_inertial(link, geoms_t), finger=finger.name)
            links.append(spec)
            by_name[link.name] = spec
            parent = link.name
            prev_len = link.length
    names = [j.name for link in links for j in link.joints]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        ctx.fail(f"duplicate joint names {sorted(dup)}")
    return links, fingers


def _check_actuators(keys, act_names: set[str], ctx: _Ctx) -> None:
    for k in keys:
        if k not in act_names:
            ctx.fail(f"{k!r} is not an actuator of this hand {sorted(act_names)}")


@functools.lru_cache(maxsize=None)
def load_hand(name: str) -> HandDescription:
    return read_hand_file(resolve("hand", name))


def read_hand_file(path: Path) -> HandDescription:
    """One hand file, validated (``load_hand`` reads the catalog's, once per process)."""
    path = Path(path)
    name = path.stem
    data, m = read_file(HandFile, path)
    ctx = _Ctx(path)
    links, fingers = _hand_links(m, ctx)
    joints = {j.name: j for link in links for j in link.joints}
    actuators = []
    for i, a in enumerate(m.actuators):
        if a.joint not in joints:
            ctx.sub(f"actuators[{i}].joint").fail(f"{a.joint!r} is not a joint of this hand")
        jspec = joints[a.joint]
        actuators.append(ActuatorSpec(
            name=a.name if a.name is not None else a.joint, joint=a.joint,
            effort=a.effort if a.effort is not None else jspec.effort,
            velocity=a.velocity if a.velocity is not None else jspec.velocity,
            kp=a.kp, kv=a.kv,
        ))
    couplings = []
    for i, c in enumerate(m.couplings or []):
        for k, n in (("joint", c.joint), ("master", c.master)):
            if n not in joints:
                ctx.sub(f"couplings[{i}].{k}").fail(f"{n!r} is not a joint of this hand")
        couplings.append(CouplingSpec(c.joint, c.master, tuple(c.polycoef + [0.0] * (5 - len(c.polycoef)))))
    driven = {a.joint for a in actuators} | {c.joint for c in couplings}
    free = set(joints) - driven
    if free:
        ctx.fail(f"joints {sorted(free)} are neither actuated nor coupled")
    both = {a.joint for a in actuators} & {c.joint for c in couplings}
    if both:
        ctx.fail(f"joints {sorted(both)} are both actuated and coupled")
    home = dict(m.home or {})
    for k in home:
        if k not in joints:
            ctx.sub("home").fail(f"{k!r} is not a joint of this hand")
    act_names = {a.name for a in actuators}
    probe = None
    if m.grasp_probe is not None:
        g = m.grasp_probe
        _check_actuators(g.close, act_names, ctx.sub("grasp_probe.close"))
        probe = GraspProbe(radius=g.radius, half_length=g.half_length, mass=g.mass, pos=np.asarray(g.pos, float),
                           axis=np.asarray(g.axis if g.axis is not None else [1, 0, 0], float), close=dict(g.close))
    tabletop = None
    if m.tabletop_grasp is not None:
        g = m.tabletop_grasp
        for field_name, keys in (("close", g.close), ("late", g.late), ("thin_close", g.thin_close)):
            _check_actuators(keys, act_names, ctx.sub(f"tabletop_grasp.{field_name}"))
        tabletop = TabletopGrasp(centre=np.asarray(g.centre, float), close=dict(g.close), late=tuple(g.late),
                                 thin_close=dict(g.thin_close))
    tactile = hand_tactile(m.tactile, ctx.sub("tactile"), {link.name for link in links}, fingers)
    real_model = None
    if m.real_model is not None:
        real_model = parse_real_model(m.real_model, ctx.sub("real_model"), links, fingers,
                                      [a.name for a in actuators], {s.attach_body for s in tactile.sites})
    return HandDescription(
        name=m.name if m.name is not None else name,
        display_name=m.display_name if m.display_name is not None else name,
        source=m.source, assumptions=m.assumptions,
        mount=frame_transform(m.mount), links=tuple(links),
        actuators=tuple(actuators), couplings=tuple(couplings),
        wrist_site=frame_transform(m.wrist_site),
        tactile=tactile,
        home=home, fingers=tuple(fingers), grasp_probe=probe, tabletop_grasp=tabletop,
        contact_exclude=contact_excludes(m.contact_exclude, ctx, {link.name for link in links}),
        servo_error_at_full_effort=m.servo_error_at_full_effort,
        path=path, real_model=real_model, heavy_side_hold=m.heavy_side_hold,
        round_pinch=None if m.round_pinch is None else RoundPinch(
            None if m.round_pinch.fingers is None else tuple(m.round_pinch.fingers),
            None if m.round_pinch.fold is None else float(m.round_pinch.fold),
            None if m.round_pinch.tips_height_m is None else float(m.round_pinch.tips_height_m)),
    )
