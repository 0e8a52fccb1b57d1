"""Declarative arm / hand / embodiment descriptions: dataclasses, YAML loading and validation.

Catalog layout (``sim/catalog``): ``arms/<name>.yaml``, ``hands/<name>.yaml``,
``embodiments/<name>.yaml``. Every file is plain data (read with ``yaml.safe_load``); the builder in
``builder.py`` turns descriptions into MuJoCo bodies and ``kinematics.py`` into a Pinocchio model.

Conventions (all lengths in metres, angles in radians):

* Arm joints follow URDF: each joint has an ``origin`` (xyz + rpy, parent link frame -> joint frame,
  which is also the child link frame) and an ``axis`` in the joint frame. ``flange`` is the tool
  flange frame in the last link's frame, with +z pointing out of the flange.
* Hands are described for the RIGHT side. Hand base = flange frame; +z along the extended fingers,
  +y the palm normal (the side fingers curl toward), +x lateral (thumb on -x for a right hand).
  The left hand is mirrored from it (see ``mirror.py``).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np
import yaml

CATALOG_DIR = Path(__file__).resolve().parent.parent / "catalog"
ARMS_DIR = CATALOG_DIR / "arms"
HANDS_DIR = CATALOG_DIR / "hands"
EMBODIMENTS_DIR = CATALOG_DIR / "embodiments"

GEOM_TYPES = ("capsule", "box", "sphere", "cylinder", "ellipsoid")
TACTILE_GROUPINGS = ("side_shared", "side_specific", "per_finger")
TACTILE_NORMAL_CONVENTIONS = ("inward", "outward")
TACTILE_SIDES = ("right", "left")
THUMB = "thumb"
PAD_FIELDS = ("center", "normal", "axis", "length", "width", "curvature_radius")


class DescriptionError(ValueError):
    """A catalog file is missing a field or holds a value of the wrong shape."""


# --------------------------------------------------------------------------------------------
# small math helpers shared by the builder and kinematics
# --------------------------------------------------------------------------------------------

def rpy_to_matrix(rpy) -> np.ndarray:
    """URDF fixed-axis roll-pitch-yaw: R = Rz(yaw) @ Ry(pitch) @ Rx(roll)."""
    r, p, y = (float(v) for v in rpy)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ])


def frame_from_axes(z, y) -> np.ndarray:
    """Rotation whose z column is ``z`` and whose y column is ``y`` orthogonalised against it."""
    z = np.asarray(z, float)
    z = z / np.linalg.norm(z)
    y = np.asarray(y, float)
    y = y - z * (y @ z)
    n = np.linalg.norm(y)
    if n < 1e-9:
        raise DescriptionError(f"frame axes z={z} and y={y} are parallel")
    y = y / n
    x = np.cross(y, z)
    return np.column_stack([x, y, z])


def mat_to_quat(R: np.ndarray) -> np.ndarray:
    """Rotation matrix -> unit quaternion (w, x, y, z), w >= 0."""
    import mujoco

    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=float).reshape(9))
    if q[0] < 0:
        q = -q
    return q


def quat_to_mat(q) -> np.ndarray:
    import mujoco

    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, np.asarray(q, float))
    return R.reshape(3, 3)


@dataclass(frozen=True)
class Transform:
    """Rigid transform (rotation matrix + translation) used for origins and mounts."""

    pos: np.ndarray
    rot: np.ndarray

    @staticmethod
    def identity() -> "Transform":
        return Transform(np.zeros(3), np.eye(3))

    def __matmul__(self, other: "Transform") -> "Transform":
        return Transform(self.pos + self.rot @ other.pos, self.rot @ other.rot)

    def inverse(self) -> "Transform":
        return Transform(-self.rot.T @ self.pos, self.rot.T)

    def to_local(self, points) -> np.ndarray:
        """Points (3,) or (n, 3) given in the parent frame, expressed in this frame."""
        return (np.asarray(points, float) - self.pos) @ self.rot

    @property
    def quat(self) -> np.ndarray:
        return mat_to_quat(self.rot)


# --------------------------------------------------------------------------------------------
# dataclasses
# --------------------------------------------------------------------------------------------

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


KEEP_SIGN_MARGIN_RAD = 0.05   # `ik_keep_sign`: the IK keeps the joint this far from zero (a straight elbow)


@dataclass(frozen=True)
class ArmDescription:
    name: str
    display_name: str
    source: str
    approximations: str
    links: tuple[LinkSpec, ...]      # base link first, then one link per joint in chain order
    flange: Transform                # in the last link frame, +z out of the flange
    home_seed: dict[str, np.ndarray]  # side -> elbow-up seed for the home IK
    servo_error_at_full_effort: float
    contact_exclude: tuple[tuple[str, str], ...]
    path: Path
    # radius (m) around the bimanual home wrist pose in which palm-down wrist poses are reached
    # (``reach.home_radius_m``, measured with ``python -m sim.embodiment.reach``)
    reach_m: float
    # joints whose IK solutions keep the sign they have in the home seed (the elbow's branch): a
    # stretched arm would otherwise flip elbow-down and drive its upper arm into the table
    ik_keep_sign: tuple[str, ...] = ()

    @property
    def joints(self) -> list[JointSpec]:
        return [j for link in self.links for j in link.joints]

    @property
    def dof(self) -> int:
        return len(self.joints)


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


@dataclass(frozen=True, eq=False)  # arrays: compare pads with same_as
class TactilePad:
    """A contact pad in its attach-body frame (metres); ``tactile.pads`` meshes its surface.

    Pad frame: origin ``center``; ``e_width = axis x normal``, ``e_axis = axis``, ``e_normal = normal``
    (right-handed). The surface is the sheet ``h(x)`` over ``|x| <= width/2`` (x along e_width),
    straight along the axis. With radius R > 0: ``a = max(0, width/2 - R)``, ``t = max(0, |x| - a)``,
    ``h = sqrt(R^2 - t^2) - R``: a circular arc for R >= width/2, a flat middle with rounded edges of
    radius R otherwise.
    """

    center: np.ndarray   # on the contact surface
    normal: np.ndarray   # unit, outward (towards objects)
    axis: np.ndarray     # unit, along the finger, orthogonal to normal
    length: float        # along axis
    width: float         # across axis
    curvature_radius: float = 0.0  # cylindrical rounding across the width; 0 = flat

    def frame(self) -> np.ndarray:
        """3x3 rotation whose columns are e_width, e_axis, e_normal (attach-body frame)."""
        n = np.asarray(self.normal, dtype=np.float64)
        a = np.asarray(self.axis, dtype=np.float64)
        return np.column_stack([np.cross(a, n), a, n])

    def profile(self, x: np.ndarray) -> np.ndarray:
        """Surface height h(x) <= 0 below the centre plane, x across the width (metres)."""
        r = self.curvature_radius
        if r == 0:
            return np.zeros_like(x, dtype=np.float64)
        t = np.maximum(0.0, np.abs(x) - max(0.0, self.width / 2 - r))
        return np.sqrt(np.maximum(r * r - t * t, 0.0)) - r

    def same_as(self, other: "TactilePad") -> bool:
        return all(np.array_equal(getattr(self, k), getattr(other, k)) for k in PAD_FIELDS)


@dataclass(frozen=True)
class TactileSite:
    name: str
    finger: str
    group: str           # surface group, e.g. "4F"
    attach_body: str
    pad: TactilePad      # the group's pad


@dataclass(frozen=True)
class TactileGroup:
    """Sites that share one surface asset per side (all carry the group's pad)."""

    name: str
    assets: dict[str, str]   # side -> asset name; equal on both sides when the asset is shared
    pad: TactilePad
    sites: tuple[str, ...]   # site names, file order


@dataclass(frozen=True)
class TactileSpec:
    """A hand file's ``tactile`` block (format: the comment before ``_TACTILE_FIELDS``): physics pads and registry."""

    grouping: str
    normal_convention: str
    resolution: int
    groups: dict[str, TactileGroup]   # file order
    sites: tuple[TactileSite, ...]
    pad_friction: tuple[float, float, float]
    pad_condim: int

    def group_of(self, site: str) -> TactileGroup:
        for s in self.sites:
            if s.name == site:
                return self.groups[s.group]
        raise KeyError(f"no tactile site '{site}'; sites: {[s.name for s in self.sites]}")

    def asset_of(self, side: str, site: str) -> str:
        """The surface asset a site uses on ``side``, e.g. ``asset_of("left", "index_tip") == "L4F"``."""
        return self.group_of(site).assets[side]

    def site_assets(self) -> dict[str, str]:
        """The site-to-asset map, sites named as in the MuJoCo model (``{side}_{site}``)."""
        return {f"{side}_{s.name}": self.asset_of(side, s.name) for side in TACTILE_SIDES for s in self.sites}


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


@dataclass(frozen=True)
class CameraSpec:
    name: str
    fovy: float
    pos: np.ndarray | None = None
    target: np.ndarray | None = None


@dataclass(frozen=True)
class EmbodimentDescription:
    name: str
    display_name: str
    arm: ArmDescription
    hand: HandDescription
    mounts: dict[str, Transform]            # side -> arm base in world
    home_wrist: Transform                    # right wrist-site home pose in world (left mirrored)
    home_arm: dict[str, np.ndarray] | None   # optional explicit arm home per side
    home_seed: dict[str, np.ndarray] | None  # optional IK seeds per side (else the arm file's)
    torso: dict[str, Any]
    cameras: dict[str, CameraSpec]
    path: Path
    # tactile registry override: site -> hand link whose frame holds the site and its pad (the pad's
    # centre, normal and axis are read in that link's frame); sites not named keep the hand file's body
    tactile_attach: dict[str, str] = field(default_factory=dict)


# --------------------------------------------------------------------------------------------
# parsing helpers
# --------------------------------------------------------------------------------------------

def _expected_error(path, where: str, expected: str, got=None) -> DescriptionError:
    got_text = f" (got {got!r})" if got is not None else ""
    return DescriptionError(f"{path}: field '{where}': expected {expected}{got_text}")


class _Ctx:
    """Carries the file path and a field path for error messages.

    ``error(path, field, expected, got)`` builds what ``expect`` raises (the tactile layer passes its
    ``TactileSpecError``); the message reads the same either way.
    """

    def __init__(self, path: Path | str | None, where: str = "", error: Callable = _expected_error):
        self.path = path
        self.where = where
        self.error = error

    def sub(self, key) -> "_Ctx":
        return _Ctx(self.path, f"{self.where}.{key}" if self.where else str(key), self.error)

    def fail(self, msg: str):
        raise DescriptionError(f"{self.path}: field '{self.where}': {msg}")

    def expect(self, expected: str, got=None):
        raise self.error(self.path, self.where, expected, got)


def _get(d: dict, key: str, ctx: _Ctx, default=Ellipsis):
    if not isinstance(d, dict):
        ctx.fail(f"expected a mapping, got {type(d).__name__}")
    if key not in d:
        if default is Ellipsis:
            ctx.sub(key).fail("missing")
        return default
    return d[key]


def _vec(v, n: int, ctx: _Ctx) -> np.ndarray:
    try:
        a = np.asarray([float(x) for x in v], dtype=float)
    except (TypeError, ValueError):
        ctx.fail(f"expected a list of {n} numbers, got {v!r}")
    if a.shape != (n,):
        ctx.fail(f"expected a list of {n} numbers, got {len(a)}")
    return a


def _num(v, ctx: _Ctx, positive: bool = False) -> float:
    try:
        x = float(v)
    except (TypeError, ValueError):
        ctx.fail(f"expected a number, got {v!r}")
    if positive and not x > 0:
        ctx.fail(f"expected a positive number, got {x}")
    return x


def _transform(d: dict | None, ctx: _Ctx) -> Transform:
    """``{xyz, rpy}`` or ``{xyz, z, y}`` (frame from axes) or ``{xyz, quat}`` (w, x, y, z)."""
    if d is None:
        return Transform.identity()
    pos = _vec(d.get("xyz", [0, 0, 0]), 3, ctx.sub("xyz"))
    if "rpy" in d:
        rot = rpy_to_matrix(_vec(d["rpy"], 3, ctx.sub("rpy")))
    elif "z" in d:
        rot = frame_from_axes(_vec(d["z"], 3, ctx.sub("z")), _vec(_get(d, "y", ctx), 3, ctx.sub("y")))
    elif "quat" in d:
        rot = quat_to_mat(_vec(d["quat"], 4, ctx.sub("quat")) / np.linalg.norm(d["quat"]))
    else:
        rot = np.eye(3)
    return Transform(pos, rot)


def _geom(d: dict, ctx: _Ctx, defaults: dict) -> GeomSpec:
    gtype = _get(d, "type", ctx)
    if gtype not in GEOM_TYPES:
        ctx.sub("type").fail(f"expected one of {GEOM_TYPES}, got {gtype!r}")
    fromto = None
    if "fromto" in d:
        fromto = _vec(d["fromto"], 6, ctx.sub("fromto"))
        size = (_num(_get(d, "radius", ctx), ctx.sub("radius"), positive=True),)
        pos, rot = np.zeros(3), np.eye(3)
    else:
        size = tuple(float(s) for s in _get(d, "size", ctx))
        tf = _transform(d, ctx)
        pos, rot = tf.pos, tf.rot
    friction = d.get("friction", defaults.get("friction"))
    condim = d.get("condim", defaults.get("condim"))
    rgba = d.get("rgba", defaults.get("rgba"))
    return GeomSpec(
        type=gtype, size=size, pos=pos, rot=rot, fromto=fromto,
        friction=tuple(float(x) for x in friction) if friction is not None else None,
        condim=int(condim) if condim is not None else None,
        rgba=tuple(float(x) for x in rgba) if rgba is not None else None,
        name=d.get("name"),
    )


def _geom_volume_inertia(g: GeomSpec) -> tuple[float, np.ndarray, np.ndarray]:
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


def _inertial(d: dict, geoms: tuple[GeomSpec, ...], ctx: _Ctx) -> Inertial:
    """Explicit ``mass`` (+ optional ``com`` and diagonal ``inertia``); what is not given is
    derived from the collision geometry at uniform density scaled to the stated mass."""
    mass = _num(_get(d, "mass", ctx), ctx.sub("mass"), positive=True)
    parts = [_geom_volume_inertia(g) for g in geoms]
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
    com = _vec(d["com"], 3, ctx.sub("com")) if "com" in d else com_geo
    inertia = _vec(d["inertia"], 3, ctx.sub("inertia")) if "inertia" in d else I
    inertia = np.maximum(inertia, 1e-7)
    return Inertial(mass, com, inertia)


def _joint(d: dict, ctx: _Ctx, defaults: dict) -> JointSpec:
    name = str(_get(d, "name", ctx))
    rng = _vec(_get(d, "range", ctx), 2, ctx.sub("range"))
    if not rng[0] < rng[1]:
        ctx.sub("range").fail(f"lower bound must be below upper bound, got {rng.tolist()}")
    axis = _vec(d.get("axis", defaults.get("axis", [0, 0, 1])), 3, ctx.sub("axis"))
    axis = axis / np.linalg.norm(axis)
    g = lambda k, dflt: _num(d.get(k, defaults.get(k, dflt)), ctx.sub(k))  # noqa: E731
    return JointSpec(
        name=name, axis=axis, range=(float(rng[0]), float(rng[1])),
        velocity=g("velocity", 3.0), effort=g("effort", 1.0), armature=g("armature", 0.0),
        damping=g("damping", 0.0), frictionloss=g("frictionloss", 0.0),
    )


def _excludes(data: dict, ctx: _Ctx, link_names: set[str]) -> tuple[tuple[str, str], ...]:
    out = []
    for i, pair in enumerate(data.get("contact_exclude", []) or []):
        c = ctx.sub(f"contact_exclude[{i}]")
        if not isinstance(pair, list) or len(pair) != 2:
            c.fail("expected a pair of link names")
        for n in pair:
            if n not in link_names:
                c.fail(f"{n!r} is not a link")
        out.append((str(pair[0]), str(pair[1])))
    return tuple(out)


def _read_yaml(path: Path) -> dict:
    with open(path, encoding="utf-8") as f:
        data = yaml.safe_load(f)
    if not isinstance(data, dict):
        raise DescriptionError(f"{path}: expected a mapping at the top level")
    return data


def _names(folder: Path) -> list[str]:
    return sorted(p.stem for p in folder.glob("*.yaml"))


def _resolve(folder: Path, name: str, kind: str) -> Path:
    path = folder / f"{name}.yaml"
    if not path.is_file():
        raise ValueError(f"unknown {kind} {name!r}; valid: {', '.join(_names(folder))}")
    return path


# --------------------------------------------------------------------------------------------
# arms
# --------------------------------------------------------------------------------------------

def arm_names() -> list[str]:
    return _names(ARMS_DIR)


@functools.lru_cache(maxsize=None)
def load_arm(name: str) -> ArmDescription:
    path = _resolve(ARMS_DIR, name, "arm")
    data = _read_yaml(path)
    ctx = _Ctx(path)
    jdefaults = data.get("joint_defaults", {}) or {}
    gdefaults = data.get("geom_defaults", {}) or {}
    base = _get(data, "base", ctx)
    bctx = ctx.sub("base")
    base_geoms = tuple(_geom(g, bctx.sub(f"geoms[{i}]"), gdefaults) for i, g in enumerate(base.get("geoms", [])))
    links = [LinkSpec(
        name=str(_get(base, "link", bctx)), parent=None, origin=Transform.identity(), joints=(),
        geoms=base_geoms, inertial=_inertial(base, base_geoms, bctx),
    )]
    chain = _get(data, "chain", ctx)
    if not isinstance(chain, list) or not chain:
        ctx.sub("chain").fail("expected a non-empty list of joints")
    flange_raw = _get(data, "flange", ctx)
    for i, entry in enumerate(chain):
        c = ctx.sub(f"chain[{i}]")
        link_raw = _get(entry, "link", c)
        if "segment_radius" in link_raw:
            # shorthand: a capsule from this joint to the next joint origin (or the flange) plus a
            # joint-housing cylinder along the joint axis
            nxt = chain[i + 1]["origin"] if i + 1 < len(chain) else flange_raw
            end = [float(v) for v in nxt.get("xyz", [0, 0, 0])]
            r = float(link_raw["segment_radius"])
            extra = list(link_raw.get("geoms", []))
            if np.linalg.norm(end) > 1e-3 and not link_raw.get("no_segment", False):
                extra.insert(0, {"type": "capsule", "fromto": [0, 0, 0] + end, "radius": r})
            ax = np.asarray(entry.get("axis", [0, 0, 1]), float)
            h = float(link_raw.get("housing_half_length", r))
            extra.append({"type": "cylinder", "fromto": list(-ax * h) + list(ax * h), "radius": r * 1.08,
                          "rgba": link_raw.get("housing_rgba", [0.3, 0.3, 0.32, 1])})
            link_raw = dict(link_raw, geoms=extra)
            entry = dict(entry, link=link_raw)
        joint = _joint(entry, c, jdefaults)
        link = _get(entry, "link", c)
        lctx = c.sub("link")
        geoms = tuple(_geom(g, lctx.sub(f"geoms[{k}]"), gdefaults) for k, g in enumerate(link.get("geoms", [])))
        links.append(LinkSpec(
            name=str(_get(link, "name", lctx)), parent=links[-1].name,
            origin=_transform(_get(entry, "origin", c), c.sub("origin")), joints=(joint,),
            geoms=geoms, inertial=_inertial(link, geoms, lctx),
        ))
    dof = len(chain)
    raw = _get(data, "home_seed", ctx)
    if isinstance(raw, dict):
        seed = {s: _vec(_get(raw, s, ctx.sub("home_seed")), dof, ctx.sub(f"home_seed.{s}")) for s in ("left", "right")}
    else:
        v = _vec(raw, dof, ctx.sub("home_seed"))
        seed = {"left": v, "right": v}
    return ArmDescription(
        name=str(data.get("name", name)), display_name=str(data.get("display_name", name)),
        source=str(_get(data, "source", ctx)), approximations=str(data.get("approximations", "")),
        links=tuple(links), flange=_transform(_get(data, "flange", ctx), ctx.sub("flange")),
        home_seed=seed,
        servo_error_at_full_effort=_num(data.get("servo_error_at_full_effort", 0.05), ctx.sub("servo_error_at_full_effort"), True),
        contact_exclude=_excludes(data, ctx, {link.name for link in links}),
        path=path,
        reach_m=_num(_get(_get(data, "reach", ctx), "home_radius_m", ctx.sub("reach")),
                     ctx.sub("reach.home_radius_m"), positive=True),
        ik_keep_sign=_keep_sign(data, ctx, [link.joints[0].name for link in links[1:]], seed),
    )


def _keep_sign(data: dict, ctx: _Ctx, joint_names: list[str], seed: dict[str, np.ndarray]) -> tuple[str, ...]:
    names = data.get("ik_keep_sign", []) or []
    if not isinstance(names, list):
        ctx.sub("ik_keep_sign").fail(f"expected a list of joint names from {joint_names}")
    for i, n in enumerate(names):
        c = ctx.sub(f"ik_keep_sign[{i}]")
        if n not in joint_names:
            c.fail(f"{n!r} is not a joint; expected one of {joint_names}")
        if any(abs(seed[s][joint_names.index(n)]) <= KEEP_SIGN_MARGIN_RAD for s in seed):
            c.fail(f"{n!r} is within {KEEP_SIGN_MARGIN_RAD} rad of zero in a home seed: no clear sign to keep")
    return tuple(str(n) for n in names)


# --------------------------------------------------------------------------------------------
# hands
# --------------------------------------------------------------------------------------------

def hand_names() -> list[str]:
    return _names(HANDS_DIR)


def _hand_links(data: dict, ctx: _Ctx) -> tuple[list[LinkSpec], list[str]]:
    jdefaults = data.get("joint_defaults", {}) or {}
    gdefaults = data.get("geom_defaults", {}) or {}
    palm = _get(data, "palm", ctx)
    pctx = ctx.sub("palm")
    pgeoms = tuple(_geom(g, pctx.sub(f"geoms[{i}]"), gdefaults) for i, g in enumerate(_get(palm, "geoms", pctx)))
    palm_link = LinkSpec(
        name=str(_get(palm, "name", pctx)), parent=None, origin=Transform.identity(), joints=(),
        geoms=pgeoms, inertial=_inertial(palm, pgeoms, pctx),
    )
    links = [palm_link]
    fingers = []
    by_name = {palm_link.name: palm_link}
    for fi, finger in enumerate(_get(data, "fingers", ctx)):
        fctx = ctx.sub(f"fingers[{fi}]")
        fname = str(_get(finger, "name", fctx))
        fingers.append(fname)
        parent = str(finger.get("parent", palm_link.name))
        prev_len = None
        for li, link in enumerate(_get(finger, "links", fctx)):
            lctx = fctx.sub(f"links[{li}]")
            lname = str(_get(link, "name", lctx))
            if lname in by_name:
                lctx.sub("name").fail(f"duplicate link name {lname!r}")
            if parent not in by_name:
                lctx.fail(f"parent link {parent!r} is not defined before it")
            origin = _transform(link.get("origin"), lctx.sub("origin"))
            if "origin" not in link or "xyz" not in link["origin"]:
                if prev_len is None:
                    lctx.sub("origin").fail("the first link of a finger needs origin.xyz on its parent")
                origin = Transform(np.array([0, 0, prev_len]), origin.rot)
            joints = tuple(_joint(j, lctx.sub(f"joints[{k}]"), jdefaults) for k, j in enumerate(link.get("joints", [])))
            length = _num(link.get("length", 0.0), lctx.sub("length"))
            geoms = [_geom(g, lctx.sub(f"geoms[{k}]"), gdefaults) for k, g in enumerate(link.get("geoms", []))]
            if "radius" in link and length > 0:
                # default phalanx: a capsule along +z from the joint to the next joint
                r = _num(link["radius"], lctx.sub("radius"), positive=True)
                geoms.insert(0, _geom({"type": "capsule", "fromto": [0, 0, 0, 0, 0, length], "radius": r},
                                      lctx, gdefaults))
            geoms_t = tuple(geoms)
            spec = LinkSpec(name=lname, parent=parent, origin=origin, joints=joints, geoms=geoms_t,
                            inertial=_inertial(link, geoms_t, lctx), finger=fname)
            links.append(spec)
            by_name[lname] = spec
            parent = lname
            prev_len = length
    names = [j.name for link in links for j in link.joints]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        ctx.fail(f"duplicate joint names {sorted(dup)}")
    return links, fingers


# The ``tactile`` block (right hand; the builder mirrors it for the left)::
#
#     tactile:
#       grouping: side_specific        # the paper's policy: side_shared | side_specific | per_finger
#       normal_convention: inward
#       resolution: 240
#       pad_friction: [1.2, 0.02, 0.002]   # optional, the pad geoms' friction and condim
#       pad_condim: 4
#       groups:                        # one surface asset per group and side
#         TH: {assets: {right: RTH, left: LTH}, pad: &TH_pad {center: ..., normal: ..., ...}}
#         4F: {assets: {right: R4F, left: L4F}, pad: &4F_pad {...}}
#       sites:                         # one per finger
#         - {name: thumb_tip, finger: thumb, group: TH, attach_body: thumb_distal, pad: *TH_pad}
#
# Policies (paper appendix "Unified Tactile Surface Reconstruction"): ``side_shared`` (thumb/4F): one
# group for the thumb, one for all other fingers, each group's one asset serving both hands
# (``assets.right == assets.left``), so its pad must be symmetric under the left/right mirror;
# ``side_specific`` (thumb/4F): the same two groups, a right and a left asset each; ``per_finger``:
# one group per site, a right and a left asset each. Every site of a group carries the group's pad
# (write ``pad: *anchor``): the builder places each site's pad geom from it, and one asset can only
# serve pads that are identical in their attach-body frames.

_TACTILE_FIELDS = ("grouping", "normal_convention", "resolution", "groups", "sites", "pad_friction", "pad_condim")
_TACTILE_GROUP_FIELDS = ("assets", "pad")
_TACTILE_SITE_FIELDS = ("name", "finger", "group", "attach_body")
PAD_UNIT_TOLERANCE = 1e-3
PAD_ORTHOGONAL_TOLERANCE = 1e-3
PAD_SYMMETRY_TOLERANCE_M = 1e-9
DEFAULT_PAD_FRICTION = (1.2, 0.02, 0.002)
DEFAULT_PAD_CONDIM = 4
PAD_CONDIMS = (1, 3, 4, 6)


def _string(value, ctx: _Ctx) -> str:
    if not isinstance(value, str) or not value:
        ctx.expect("a non-empty string", value)
    return value


def _mapping(raw, ctx: _Ctx, keys) -> dict:
    if not isinstance(raw, dict):
        ctx.expect("a mapping with " + ", ".join(keys), raw)
    unknown = sorted(str(k) for k in set(raw) - set(keys))
    if unknown:
        ctx.sub(unknown[0]).expect("one of " + ", ".join(keys), "unknown")
    return raw


def _pad_vector(raw: dict, key: str, ctx: _Ctx) -> np.ndarray:
    value = raw.get(key)
    try:
        vec = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        vec = None
    if vec is None or vec.shape != (3,) or not np.all(np.isfinite(vec)):
        ctx.sub(key).expect("a list of 3 finite numbers", value)
    return vec


def _pad_length(value, ctx: _Ctx, allow_zero: bool = False) -> float:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or value < 0 or (value == 0 and not allow_zero):
        ctx.expect("a number >= 0 (metres)" if allow_zero else "a positive number (metres)", value)
    return float(value)


def _pad(raw, ctx: _Ctx) -> TactilePad:
    if not isinstance(raw, dict):
        ctx.expect("a mapping with " + ", ".join(PAD_FIELDS), raw)
    missing = [k for k in PAD_FIELDS if k not in raw and k != "curvature_radius"]
    if missing:
        ctx.sub(missing[0]).expect("a value (field is missing)")
    _mapping(raw, ctx, PAD_FIELDS)
    center, normal, axis = (_pad_vector(raw, k, ctx) for k in ("center", "normal", "axis"))
    for key, vec in (("normal", normal), ("axis", axis)):
        if abs(np.linalg.norm(vec) - 1.0) > PAD_UNIT_TOLERANCE:
            ctx.sub(key).expect("a unit vector", vec.tolist())
    if abs(float(normal @ axis)) > PAD_ORTHOGONAL_TOLERANCE:
        ctx.sub("axis").expect("a vector orthogonal to normal", axis.tolist())
    normal = normal / np.linalg.norm(normal)
    axis = axis - (axis @ normal) * normal
    return TactilePad(
        center=center, normal=normal, axis=axis / np.linalg.norm(axis),
        length=_pad_length(raw.get("length"), ctx.sub("length")),
        width=_pad_length(raw.get("width"), ctx.sub("width")),
        curvature_radius=_pad_length(raw.get("curvature_radius", 0.0), ctx.sub("curvature_radius"), True),
    )


def parse_tactile_pad(raw, source=None, field: str = "pad", error: Callable = _expected_error) -> TactilePad:
    """Validate one ``pad`` mapping; errors (built by ``error``) name ``source`` and the dotted field path."""
    return _pad(raw, _Ctx(source, field, error))


def _pad_is_mirror_symmetric(pad: TactilePad) -> bool:
    from .mirror import mirror_vec  # late: mirror builds on this module

    return all(np.allclose(mirror_vec(v), v, atol=PAD_SYMMETRY_TOLERANCE_M, rtol=0)
               for v in (pad.center, pad.normal, pad.axis))


def _tactile_sites(entries, pads: dict[str, TactilePad], ctx: _Ctx, link_names: set[str],
                   fingers: list[str]) -> list[TactileSite]:
    if not isinstance(entries, list) or not entries:
        ctx.sub("sites").expect("a non-empty list of sites", entries)
    sites: list[TactileSite] = []
    for i, entry in enumerate(entries):
        sctx = ctx.sub(f"sites[{i}]")
        entry = _mapping(entry, sctx, (*_TACTILE_SITE_FIELDS, "pad"))
        name, finger, group, body = (_string(entry.get(k), sctx.sub(k)) for k in _TACTILE_SITE_FIELDS)
        if any(s.name == name for s in sites):
            sctx.sub("name").expect("a site name unique in the hand", name)
        if finger not in fingers:
            sctx.sub("finger").expect("one of the fingers " + ", ".join(fingers), finger)
        if body not in link_names:
            sctx.sub("attach_body").expect("a link of this hand", body)
        if group not in pads:
            sctx.sub("group").expect("one of the groups " + ", ".join(pads), group)
        expected = f"the pad of group '{group}' (tactile.groups.{group}.pad; write pad: *anchor)"
        if "pad" not in entry or not _pad(entry["pad"], sctx.sub("pad")).same_as(pads[group]):
            sctx.sub("pad").expect(expected)
        sites.append(TactileSite(name, finger, group, body, pads[group]))
    covered = {s.finger for s in sites}
    if covered != set(fingers):
        ctx.sub("sites").expect(f"one site per finger {fingers}", sorted(covered))
    return sites


def _check_tactile_policy(grouping: str, groups: dict[str, TactileGroup], sites: list[TactileSite], ctx: _Ctx):
    """The grouping policy's shape: which sites share a group, and whether sides share assets."""
    thumb = {s.name for s in sites if s.finger == THUMB}
    others = {s.name for s in sites if s.finger != THUMB}
    for name, group in groups.items():
        gctx = ctx.sub(f"groups.{name}")
        members = set(group.sites)
        if not members:
            gctx.expect("at least one site (no site names this group)")
        if grouping == "per_finger" and len(members) != 1:
            gctx.expect("one site per group under grouping per_finger", sorted(members))
        if grouping != "per_finger" and members not in (thumb, others):
            gctx.expect(f"either the thumb sites {sorted(thumb)} or all other sites {sorted(others)} "
                        f"(grouping {grouping}: thumb/4F)", sorted(members))
        right, left = group.assets["right"], group.assets["left"]
        if grouping == "side_shared" and right != left:
            gctx.sub("assets").expect("one asset for both sides (grouping side_shared)", group.assets)
        if grouping != "side_shared" and right == left:
            gctx.sub("assets").expect(f"different right and left assets (grouping {grouping})", group.assets)
        if grouping == "side_shared" and not _pad_is_mirror_symmetric(group.pad):
            gctx.sub("pad").expect("a pad symmetric under the left/right mirror (x = 0 in center, normal and "
                                   "axis) so that one asset serves both hands")
    owner: dict[str, str] = {}
    for name, group in groups.items():
        for side in TACTILE_SIDES:
            asset = group.assets[side]
            if owner.setdefault(asset, name) != name:
                ctx.sub(f"groups.{name}.assets.{side}").expect(f"an asset name not used by group '{owner[asset]}'",
                                                               asset)


def _tactile_block(raw, ctx: _Ctx, link_names: set[str], fingers: list[str]) -> TactileSpec:
    raw = _mapping(raw, ctx, _TACTILE_FIELDS)
    grouping = raw.get("grouping")
    if grouping not in TACTILE_GROUPINGS:
        ctx.sub("grouping").expect("one of " + ", ".join(TACTILE_GROUPINGS), grouping)
    convention = raw.get("normal_convention")
    if convention not in TACTILE_NORMAL_CONVENTIONS:
        ctx.sub("normal_convention").expect("one of " + ", ".join(TACTILE_NORMAL_CONVENTIONS), convention)
    resolution = raw.get("resolution")
    if not isinstance(resolution, int) or isinstance(resolution, bool) or resolution < 1:
        ctx.sub("resolution").expect("a positive integer", resolution)
    friction = _vec(raw.get("pad_friction", DEFAULT_PAD_FRICTION), 3, ctx.sub("pad_friction"))
    condim = raw.get("pad_condim", DEFAULT_PAD_CONDIM)
    if condim not in PAD_CONDIMS or isinstance(condim, bool):
        ctx.sub("pad_condim").expect("one of " + ", ".join(map(str, PAD_CONDIMS)), condim)
    raw_groups = raw.get("groups")
    if not isinstance(raw_groups, dict) or not raw_groups:
        ctx.sub("groups").expect("a mapping of group name -> {assets, pad}", raw_groups)
    assets, pads = {}, {}
    for name, g in raw_groups.items():
        gctx = ctx.sub(f"groups.{name}")
        g = _mapping(g, gctx, _TACTILE_GROUP_FIELDS)
        sides = _mapping(g.get("assets"), gctx.sub("assets"), TACTILE_SIDES)
        assets[str(name)] = {side: _string(sides.get(side), gctx.sub(f"assets.{side}")) for side in TACTILE_SIDES}
        pads[str(name)] = _pad(g.get("pad"), gctx.sub("pad"))
    sites = _tactile_sites(raw.get("sites"), pads, ctx, link_names, fingers)
    groups = {name: TactileGroup(name, assets[name], pads[name], tuple(s.name for s in sites if s.group == name))
              for name in pads}
    _check_tactile_policy(grouping, groups, sites, ctx)
    return TactileSpec(grouping=grouping, normal_convention=convention, resolution=resolution, groups=groups,
                       sites=tuple(sites), pad_friction=tuple(float(x) for x in friction), pad_condim=int(condim))


def parse_tactile_block(raw, source, link_names: set[str], fingers: list[str], field: str = "tactile") -> TactileSpec:
    """Validate a hand's ``tactile`` mapping against its links and fingers (``source`` names the file in errors)."""
    return _tactile_block(raw, _Ctx(source, field), set(link_names), list(fingers))


def _tactile(data: dict, ctx: _Ctx, link_names: set[str], fingers: list[str]) -> TactileSpec:
    return _tactile_block(_get(data, "tactile", ctx), ctx.sub("tactile"), link_names, fingers)


def _check_actuators(keys, act_names: set[str], ctx: _Ctx) -> None:
    for k in keys:
        if k not in act_names:
            ctx.fail(f"{k!r} is not an actuator of this hand {sorted(act_names)}")


@functools.lru_cache(maxsize=None)
def load_hand(name: str) -> HandDescription:
    return read_hand_file(_resolve(HANDS_DIR, name, "hand"))


def read_hand_file(path: Path) -> HandDescription:
    """One hand file, validated (``load_hand`` reads the catalog's, once per process)."""
    path = Path(path)
    name = path.stem
    data = _read_yaml(path)
    ctx = _Ctx(path)
    links, fingers = _hand_links(data, ctx)
    joint_names = {j.name for link in links for j in link.joints}
    actuators = []
    for i, a in enumerate(_get(data, "actuators", ctx)):
        actx = ctx.sub(f"actuators[{i}]")
        jn = str(_get(a, "joint", actx))
        if jn not in joint_names:
            actx.sub("joint").fail(f"{jn!r} is not a joint of this hand")
        jspec = next(j for link in links for j in link.joints if j.name == jn)
        actuators.append(ActuatorSpec(
            name=str(a.get("name", jn)), joint=jn,
            effort=_num(a.get("effort", jspec.effort), actx.sub("effort"), True),
            velocity=_num(a.get("velocity", jspec.velocity), actx.sub("velocity"), True),
            kp=float(a["kp"]) if "kp" in a else None, kv=float(a["kv"]) if "kv" in a else None,
        ))
    couplings = []
    for i, c in enumerate(data.get("couplings", []) or []):
        cctx = ctx.sub(f"couplings[{i}]")
        jn, mn = str(_get(c, "joint", cctx)), str(_get(c, "master", cctx))
        for k, n in (("joint", jn), ("master", mn)):
            if n not in joint_names:
                cctx.sub(k).fail(f"{n!r} is not a joint of this hand")
        coef = [float(x) for x in _get(c, "polycoef", cctx)]
        if not 1 <= len(coef) <= 5:
            cctx.sub("polycoef").fail("expected 1 to 5 coefficients")
        couplings.append(CouplingSpec(jn, mn, tuple(coef + [0.0] * (5 - len(coef)))))
    driven = {a.joint for a in actuators} | {c.joint for c in couplings}
    free = joint_names - driven
    if free:
        ctx.fail(f"joints {sorted(free)} are neither actuated nor coupled")
    both = {a.joint for a in actuators} & {c.joint for c in couplings}
    if both:
        ctx.fail(f"joints {sorted(both)} are both actuated and coupled")
    home = {str(k): float(v) for k, v in (data.get("home") or {}).items()}
    for k in home:
        if k not in joint_names:
            ctx.sub("home").fail(f"{k!r} is not a joint of this hand")
    act_names = {a.name for a in actuators}
    probe = None
    if "grasp_probe" in data:
        g = data["grasp_probe"]
        gctx = ctx.sub("grasp_probe")
        close = {str(k): float(v) for k, v in _get(g, "close", gctx).items()}
        _check_actuators(close, act_names, gctx.sub("close"))
        probe = GraspProbe(
            radius=_num(_get(g, "radius", gctx), gctx.sub("radius"), True),
            half_length=_num(_get(g, "half_length", gctx), gctx.sub("half_length"), True),
            mass=_num(_get(g, "mass", gctx), gctx.sub("mass"), True),
            pos=_vec(_get(g, "pos", gctx), 3, gctx.sub("pos")),
            axis=_vec(g.get("axis", [1, 0, 0]), 3, gctx.sub("axis")),
            close=close,
        )
    tabletop = None
    if "tabletop_grasp" in data:
        g = data["tabletop_grasp"]
        gctx = ctx.sub("tabletop_grasp")
        close = {str(k): float(v) for k, v in _get(g, "close", gctx).items()}
        late = tuple(str(k) for k in g.get("late", []))
        for field_name, keys in (("close", close), ("late", late)):
            _check_actuators(keys, act_names, gctx.sub(field_name))
        tabletop = TabletopGrasp(centre=_vec(_get(g, "centre", gctx), 3, gctx.sub("centre")), close=close, late=late)
    tactile = _tactile(data, ctx, {link.name for link in links}, fingers)
    real_model = None
    if "real_model" in data:
        from .real_model import parse_real_model   # late: real_model builds on this module

        real_model = parse_real_model(data["real_model"], ctx.sub("real_model"), links, fingers,
                                      [a.name for a in actuators], {s.attach_body for s in tactile.sites})
    return HandDescription(
        name=str(data.get("name", name)), display_name=str(data.get("display_name", name)),
        source=str(_get(data, "source", ctx)), assumptions=str(data.get("assumptions", "")),
        mount=_transform(data.get("mount"), ctx.sub("mount")), links=tuple(links),
        actuators=tuple(actuators), couplings=tuple(couplings),
        wrist_site=_transform(_get(data, "wrist_site", ctx), ctx.sub("wrist_site")),
        tactile=tactile,
        home=home, fingers=tuple(fingers), grasp_probe=probe, tabletop_grasp=tabletop,
        contact_exclude=_excludes(data, ctx, {link.name for link in links}),
        servo_error_at_full_effort=_num(data.get("servo_error_at_full_effort", 0.1), ctx.sub("servo_error_at_full_effort"), True),
        path=path, real_model=real_model,
    )


# --------------------------------------------------------------------------------------------
# embodiments
# --------------------------------------------------------------------------------------------

CAMERA_NAMES = ("chest", "overhead", "stereo_left", "stereo_right", "left_wrist", "right_wrist")
DEFAULT_FOVY = {"chest": 70.0, "overhead": 60.0, "stereo_left": 60.0, "stereo_right": 60.0,
                "left_wrist": 80.0, "right_wrist": 80.0}


def embodiment_names() -> list[str]:
    """Names of the embodiment files in ``sim/catalog/embodiments``."""
    return _names(EMBODIMENTS_DIR)


@functools.lru_cache(maxsize=None)
def load_embodiment(name: str) -> EmbodimentDescription:
    path = _resolve(EMBODIMENTS_DIR, name, "embodiment")
    data = _read_yaml(path)
    ctx = _Ctx(path)
    arm = load_arm(str(_get(data, "arm", ctx)))
    hand = load_hand(str(_get(data, "hand", ctx)))
    clash = ({lk.name for lk in arm.links} & {lk.name for lk in hand.links}) | \
        ({j.name for j in arm.joints} & {j.name for j in hand.joints})
    if clash:
        ctx.fail(f"arm {arm.name!r} and hand {hand.name!r} share link/joint names {sorted(clash)}; rename them in the hand file")
    mount = _get(data, "mount", ctx)
    mounts = {side: _transform(_get(mount, side, ctx.sub("mount")), ctx.sub(f"mount.{side}"))
              for side in ("left", "right")}
    home = _get(data, "home", ctx)
    hctx = ctx.sub("home")
    home_wrist = _transform(_get(home, "right_wrist", hctx), hctx.sub("right_wrist"))
    home_arm = None
    if "arm" in home:
        home_arm = {s: _vec(_get(home["arm"], s, hctx.sub("arm")), arm.dof, hctx.sub(f"arm.{s}"))
                    for s in ("left", "right")}
    home_seed = None
    if "seed" in home:
        home_seed = {s: _vec(_get(home["seed"], s, hctx.sub("seed")), arm.dof, hctx.sub(f"seed.{s}"))
                     for s in ("left", "right")}
    cams = data.get("cameras", {}) or {}
    unknown = set(cams) - set(CAMERA_NAMES)
    if unknown:
        ctx.sub("cameras").fail(f"unknown cameras {sorted(unknown)}; valid: {list(CAMERA_NAMES)}")
    cameras = {}
    for cname in CAMERA_NAMES:
        c = cams.get(cname, {}) or {}
        cc = ctx.sub(f"cameras.{cname}")
        cameras[cname] = CameraSpec(
            name=cname, fovy=_num(c.get("fovy", DEFAULT_FOVY[cname]), cc.sub("fovy"), True),
            pos=_vec(c["pos"], 3, cc.sub("pos")) if "pos" in c else None,
            target=_vec(c["target"], 3, cc.sub("target")) if "target" in c else None,
        )
    return EmbodimentDescription(
        name=str(data.get("name", name)), display_name=str(_get(data, "display_name", ctx)),
        arm=arm, hand=hand, mounts=mounts, home_wrist=home_wrist, home_arm=home_arm, home_seed=home_seed,
        torso=dict(data.get("torso", {}) or {}), cameras=cameras, path=path,
        tactile_attach=_tactile_attach(data.get("tactile_attach") or {}, hand, ctx.sub("tactile_attach")),
    )


def _tactile_attach(raw, hand: HandDescription, ctx: _Ctx) -> dict[str, str]:
    """The embodiment's per-site attach-body overrides, checked against the hand's sites and links."""
    if not isinstance(raw, dict):
        ctx.fail(f"expected a mapping of tactile site -> hand link, got {raw!r}")
    sites = [s.name for s in hand.tactile.sites]
    links = {lk.name for lk in hand.links}
    out = {}
    for site, link in raw.items():
        if site not in sites:
            ctx.sub(str(site)).fail(f"expected a tactile site of hand {hand.name!r} {sites}")
        if link not in links:
            ctx.sub(str(site)).fail(f"expected a link of hand {hand.name!r}, got {link!r}")
        if hand.real_model is not None and link not in hand.real_model.bodies:   # must exist on both hand models
            ctx.sub(str(site)).fail(f"expected a link mapped in hand {hand.name!r}'s real_model.bodies "
                                    f"{sorted(hand.real_model.bodies)}, got {link!r}")
        out[str(site)] = str(link)
    return out
