"""Links of a kinematic tree (geoms, joints, mass properties) built from validated arm and hand files.

Mass properties not given are derived from the collision geometry at uniform density, scaled to the
stated mass."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from sim.schema.robot_parts import GEOM_TYPES, Geom, GeomDefaults, Joint, JointDefaults, MassProperties  # noqa: F401

from .fields import _Ctx
from .frames import Transform, frame_transform

NO_JOINT_DEFAULTS = JointDefaults()
NO_GEOM_DEFAULTS = GeomDefaults()


@dataclass(frozen=True)
class GeomSpec:
    type: str
    size: tuple[float, ...]          # MuJoCo sizes (half sizes for box; radius[, half length])
    pos: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rot: np.ndarray = field(default_factory=lambda: np.eye(3))
    fromto: np.ndarray | None = None  # capsule / cylinder end points, link frame
    friction: tuple[float, float, float] | None = None
    condim: int | None = None
    rgba: tuple[float, float, float, float] | None = None
    name: str | None = None

    def support(self, u: np.ndarray) -> np.ndarray:
        """The point of the geom (link frame) furthest along unit ``u`` (link frame)."""
        if self.type in ("capsule", "cylinder"):
            if self.fromto is not None:
                a, b = np.asarray(self.fromto[:3], float), np.asarray(self.fromto[3:], float)
            else:
                half = self.rot[:, 2] * self.size[1]
                a, b = self.pos - half, self.pos + half
            end = a if u @ a >= u @ b else b
            if self.type == "capsule":
                return end + self.size[0] * u
            w = (b - a) / max(np.linalg.norm(b - a), 1e-12)
            radial = u - (u @ w) * w
            return end + self.size[0] * radial / max(np.linalg.norm(radial), 1e-12)
        if self.type == "box":
            return self.pos + self.rot @ (np.sign(self.rot.T @ u) * np.asarray(self.size[:3]))
        return self.pos + self.size[0] * u      # sphere (and, as its bounding sphere, anything else)


@dataclass(frozen=True)
class Inertial:
    mass: float
    com: np.ndarray
    inertia: np.ndarray   # diagonal (ixx, iyy, izz) about the com, link axes


@dataclass(frozen=True)
class JointSpec:
    name: str
    axis: np.ndarray
    range: tuple[float, float]
    velocity: float = 3.0            # rad/s, real max joint speed
    effort: float = 1.0              # N m, real max torque
    armature: float = 0.0
    damping: float = 0.0
    frictionloss: float = 0.0


@dataclass(frozen=True)
class LinkSpec:
    """A body of the kinematic tree. ``origin`` places it in its parent's frame."""

    name: str
    parent: str | None
    origin: Transform
    joints: tuple[JointSpec, ...]
    geoms: tuple[GeomSpec, ...]
    inertial: Inertial
    finger: str | None = None



def build_geom(g: Geom, defaults: GeomDefaults = NO_GEOM_DEFAULTS) -> GeomSpec:
    """A GeomSpec from a validated geom; friction, condim and rgba fall back to the file's geom_defaults."""
    if g.fromto is not None:
        fromto = np.asarray(g.fromto, dtype=float)
        size, pos, rot = (g.radius,), np.zeros(3), np.eye(3)
    else:
        fromto = None
        size = tuple(g.size)
        tf = frame_transform(g)
        pos, rot = tf.pos, tf.rot
    friction = g.friction if g.friction is not None else defaults.friction
    condim = g.condim if g.condim is not None else defaults.condim
    rgba = g.rgba if g.rgba is not None else defaults.rgba
    return GeomSpec(
        type=g.type, size=size, pos=pos, rot=rot, fromto=fromto,
        friction=tuple(friction) if friction is not None else None,
        condim=condim, rgba=tuple(rgba) if rgba is not None else None, name=g.name,
    )


def geom_volume_inertia(g: GeomSpec) -> tuple[float, np.ndarray, np.ndarray]:
    """Volume, centre and diagonal unit-density inertia (about its centre, link axes; the
    orientation of capsules/cylinders is folded in by projecting onto the link axes)."""
    if g.fromto is not None:
        a, b = g.fromto[:3], g.fromto[3:]
        r = g.size[0]
        L = float(np.linalg.norm(b - a))
        c = (a + b) / 2
        u = (b - a) / L if L > 1e-9 else np.array([0, 0, 1.0])
        if g.type == "capsule":
            vol = math.pi * r * r * (L + 4 * r / 3)
            h = L + 2 * r * 0.75   # treat as an equivalent cylinder for the inertia
        else:
            vol = math.pi * r * r * L
            h = L
        i_ax = 0.5 * r * r
        i_tr = (3 * r * r + h * h) / 12
        I = i_tr * np.eye(3) + (i_ax - i_tr) * np.outer(u, u)
        return vol, c, np.diag(I) * vol
    s = g.size
    if g.type == "box":
        vol = 8 * s[0] * s[1] * s[2]
        d = np.array([s[1] ** 2 + s[2] ** 2, s[0] ** 2 + s[2] ** 2, s[0] ** 2 + s[1] ** 2]) / 3
    elif g.type == "sphere":
        vol = 4 / 3 * math.pi * s[0] ** 3
        d = np.full(3, 0.4 * s[0] ** 2)
    elif g.type == "ellipsoid":
        vol = 4 / 3 * math.pi * s[0] * s[1] * s[2]
        d = np.array([s[1] ** 2 + s[2] ** 2, s[0] ** 2 + s[2] ** 2, s[0] ** 2 + s[1] ** 2]) / 5
    else:  # capsule / cylinder given by size (radius, half length) along the local z
        r, hl = s[0], s[1]
        vol = math.pi * r * r * 2 * hl
        d = np.array([(3 * r * r + 4 * hl * hl) / 12] * 2 + [0.5 * r * r])
    I = g.rot @ np.diag(d) @ g.rot.T
    return vol, g.pos, np.abs(np.diag(I)) * vol




def build_inertial(link: MassProperties, geoms: tuple[GeomSpec, ...]) -> Inertial:
    """Explicit ``mass`` (+ optional ``com`` and diagonal ``inertia``); what is not given is
    derived from the collision geometry at uniform density scaled to the stated mass."""
    mass = link.mass
    parts = [geom_volume_inertia(g) for g in geoms]
    vol = sum(p[0] for p in parts)
    if vol > 0:
        com_geo = sum(p[0] * p[1] for p in parts) / vol
        rho = mass / vol
        I = np.zeros(3)
        for v, c, Ig in parts:
            r = c - com_geo
            I += rho * Ig + rho * v * (r @ r - r * r)   # parallel axis (diagonal terms)
    else:
        com_geo = np.zeros(3)
        I = np.full(3, mass * 1e-4)
    com = np.asarray(link.com, dtype=float) if link.com is not None else com_geo
    inertia = np.asarray(link.inertia, dtype=float) if link.inertia is not None else I
    inertia = np.maximum(inertia, 1e-7)
    return Inertial(mass, com, inertia)


def build_joint(j: Joint, defaults: JointDefaults = NO_JOINT_DEFAULTS) -> JointSpec:
    """A JointSpec; what the joint leaves out comes from the file's joint_defaults, then the built-in ones."""
    def pick(key, builtin):
        value = getattr(j, key)
        if value is None:
            value = getattr(defaults, key)
        return builtin if value is None else value

    axis = np.asarray(pick("axis", [0, 0, 1]), dtype=float)
    return JointSpec(
        name=j.name, axis=axis / np.linalg.norm(axis), range=(j.range[0], j.range[1]),
        velocity=pick("velocity", 3.0), effort=pick("effort", 1.0), armature=pick("armature", 0.0),
        damping=pick("damping", 0.0), frictionloss=pick("frictionloss", 0.0),
    )


def contact_excludes(pairs, ctx: _Ctx, link_names: set[str]) -> tuple[tuple[str, str], ...]:
    """`contact_exclude` pairs, each naming two links of this file."""
    out = []
    for i, pair in enumerate(pairs or []):
        for n in pair:
            if n not in link_names:
                ctx.sub(f"contact_exclude[{i}]").fail(f"{n!r} is not a link")
        out.append((pair[0], pair[1]))
    return tuple(out)
