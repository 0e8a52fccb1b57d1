"""Schema pieces shared by arm and hand files: frames, geoms, joints, links' mass properties."""

from __future__ import annotations

import math
from typing import Annotated, ClassVar, Generic, Literal, TypeVar

from pydantic import Field, model_validator

from .base import CatalogModel, Name, NonNegativeNumber, Number, PositiveNumber, Vec3, Vec4, ranged

GEOM_TYPES = ("capsule", "box", "sphere", "cylinder", "ellipsoid")
CONDIMS = (1, 3, 4, 6)
# Sane bounds: the bench is a 1.2 x 0.8 m table between two arms, so a coordinate or a length beyond 10 m, an
# angle beyond a full turn or a body over 100 kg is a typo in the file, not a robot.
SPAN_M = 10.0
TURN_RAD = 6.3          # a full turn (2 pi = 6.2832; vendor files round it up) and no more
MAX_MASS_KG = 100.0
Coord = Annotated[Number, ranged(ge=-SPAN_M, le=SPAN_M, unit="m")]
Length = Annotated[Number, ranged(gt=0, le=SPAN_M, unit="m")]
Angle = Annotated[Number, ranged(ge=-TURN_RAD, le=TURN_RAD, unit="rad")]
Mass = Annotated[Number, ranged(gt=0, le=MAX_MASS_KG, unit="kg")]
Point3 = Annotated[list[Coord], Field(min_length=3, max_length=3)]
Vec6 = Annotated[list[Coord], Field(min_length=6, max_length=6)]
Rgba = Annotated[list[Annotated[Number, Field(ge=0, le=1)]], Field(min_length=4, max_length=4)]
Friction = Annotated[list[NonNegativeNumber], Field(min_length=3, max_length=3)]
Condim = Literal[CONDIMS]
Range = Annotated[list[Angle], Field(min_length=2, max_length=2)]


T = TypeVar("T")


class PerSide(CatalogModel, Generic[T]):
    """One value for each hand: `{right: ..., left: ...}`."""

    keys_label: ClassVar[str] = "a side"

    right: T
    left: T


class Frame(CatalogModel):
    """A pose: `xyz` plus one of `rpy` (URDF roll-pitch-yaw), `z` + `y` (frame from axes) or `quat` (w, x, y, z)."""

    xyz: Point3 | None = None
    rpy: Annotated[list[Angle], Field(min_length=3, max_length=3)] | None = None
    z: Vec3 | None = None
    y: Vec3 | None = None
    quat: Vec4 | None = None

    @model_validator(mode="after")
    def _one_rotation(self):
        given = [k for k in ("rpy", "z", "quat") if getattr(self, k) is not None]
        if len(given) > 1:
            raise ValueError(f"one rotation, rpy, z + y or quat, not {' and '.join(given)}")
        if (self.z is None) != (self.y is None):
            raise ValueError("z and y together (a frame from its z axis and a y hint)")
        if self.quat is not None and not any(self.quat):
            raise ValueError("a non-zero quaternion")
        if self.z is not None and _parallel(self.z, self.y):
            raise ValueError("z and y axes that are not parallel (nor zero)")
        return self


def _parallel(z, y) -> bool:
    """As `sim.embodiment.frames.frame_from_axes` sees them: y has nothing left once z is taken out."""
    nz = math.sqrt(sum(v * v for v in z))
    if nz < 1e-12:
        return True
    u = [v / nz for v in z]
    dot = sum(a * b for a, b in zip(u, y))
    rest = [b - a * dot for a, b in zip(u, y)]
    return math.sqrt(sum(v * v for v in rest)) < 1e-9


class Geom(Frame):
    """A collision geom: MuJoCo `size` at a pose, or `fromto` + `radius` for capsules and cylinders."""

    type: Literal[GEOM_TYPES]
    size: Annotated[list[Length], Field(min_length=1, max_length=3)] | None = None
    fromto: Vec6 | None = None
    radius: Length | None = None
    friction: Friction | None = None
    condim: Condim | None = None
    rgba: Rgba | None = None
    name: Name | None = None

    @model_validator(mode="after")
    def _sized(self):
        if self.fromto is not None and self.radius is None:
            raise ValueError("a radius with fromto")
        if self.fromto is None and self.size is None:
            raise ValueError("size (or fromto + radius)")
        return self


class GeomDefaults(CatalogModel):
    friction: Friction | None = None
    condim: Condim | None = None
    rgba: Rgba | None = None


class JointDefaults(CatalogModel):
    axis: Vec3 | None = None
    velocity: PositiveNumber | None = None      # rad/s
    effort: PositiveNumber | None = None        # N m
    armature: NonNegativeNumber | None = None
    damping: NonNegativeNumber | None = None
    frictionloss: NonNegativeNumber | None = None


class Joint(JointDefaults):
    name: Name
    range: Range

    @model_validator(mode="after")
    def _ordered(self):
        if not self.range[0] < self.range[1]:
            raise ValueError("range: lower bound below upper bound")
        if self.axis is not None and not any(self.axis):
            raise ValueError("a non-zero axis")
        return self


class MassProperties(CatalogModel):
    """`mass` (kg); `com` and diagonal `inertia` are derived from the geoms when left out."""

    mass: Mass
    com: Point3 | None = None
    inertia: Annotated[list[NonNegativeNumber], Field(min_length=3, max_length=3)] | None = None
    geoms: list[Geom] = []


LinkPair = Annotated[list[Name], Field(min_length=2, max_length=2, description="a pair of link names")]
