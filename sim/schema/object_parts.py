"""Schema of a task object's geometry and joints: `shape` + `size`, `parts` (primitives, generated open
shapes, meshes), `links` and `key_rows`. sim/scene/parts.py and sim/scene/articulated.py build the
parts and links from these checked models; a mesh's file is checked where it is read, against the task
file's folder (sim/scene/mesh_files.py).
"""

from __future__ import annotations

from typing import Annotated, Any, ClassVar, Literal

from pydantic import Field, ValidationInfo, field_validator, model_validator

from .base import CatalogModel, Int, Name, NonNegativeNumber, Number, PositiveNumber, Vec2, Vec3, ranged
from .robot_parts import Point3, Rgba

# Sane physical bounds for task objects and links. Below a gram a body is too light for the 2 ms
# step against hands of a few hundred grams; the catalog's heaviest fixed base (a toilet) is 20 kg.
MASS_RANGE_KG = (0.001, 100.0)
# Sliding friction of real material pairs, from PTFE (~0.05) to rubber on a dry surface (~2).
FRICTION_RANGE = (0.05, 2.0)
# Rolling resistance length (MuJoCo's third friction coefficient); soft fruit is about 0.001 m.
ROLLING_FRICTION_RANGE_M = (0.0, 0.01)
# From foams and hollow shells (~10 kg/m^3) to the densest metals (~22,600 kg/m^3).
DENSITY_RANGE_KG_M3 = (10.0, 25000.0)

SHAPE_SIZE_LEN = {"box": 3, "cylinder": 2, "sphere": 1, "ellipsoid": 3, "capsule": 2}    # MuJoCo half sizes
SHAPES = tuple(SHAPE_SIZE_LEN)
GENERATORS = ("open_box", "open_cylinder")
PART_KINDS = ("shape", "mesh", *GENERATORS)
OPEN_SIDES = ("+x", "-x", "+y", "-y", "+z", "-z")
MIN_SEGMENTS = 6
JOINT_KINDS = ("hinge", "slide")
DEFAULT_ARMATURE = 1e-4   # a little rotor inertia keeps light links stable at the 2 ms step

Sizes = list[PositiveNumber]
Mass = Annotated[Number, ranged(ge=MASS_RANGE_KG[0], le=MASS_RANGE_KG[1], unit="kg")]


def shape_size(size: list[float], info: ValidationInfo) -> list[float]:
    """`size` as long as its `shape` (validated before it) has half sizes."""
    shape = info.data.get("shape")
    if shape in SHAPE_SIZE_LEN and len(size) != SHAPE_SIZE_LEN[shape]:
        raise ValueError(f"{SHAPE_SIZE_LEN[shape]} positive half sizes for a {shape}")
    return size


def _thin_wall(wall: float, info: ValidationInfo) -> float:
    size = info.data.get("size")
    if size and 2 * wall >= min(size):
        raise ValueError(f"a wall less than half the smallest size ({min(size)})")
    return wall


class OpenBox(CatalogModel):
    """A box with one open face: five slabs of thickness `wall` inside the outer half size."""

    keys_label: ClassVar[str] = "a key of open_box"

    size: Annotated[Sizes, Field(min_length=3, max_length=3)]
    wall: PositiveNumber = Field(description="a number > 0 m")
    open: Literal[OPEN_SIDES] = "+z"

    _wall = field_validator("wall")(_thin_wall)


class OpenCylinder(CatalogModel):
    """An open-top cylinder [radius, half height]: a floor disc and `segments` wall slabs."""

    keys_label: ClassVar[str] = "a key of open_cylinder"

    size: Annotated[Sizes, Field(min_length=2, max_length=2)]
    wall: PositiveNumber = Field(description="a number > 0 m")
    segments: Int = Field(16, ge=MIN_SEGMENTS)

    _wall = field_validator("wall")(_thin_wall)


class PartEntry(CatalogModel):
    """One entry of a `parts` list: a primitive {shape, size}, a mesh, or a generated open shape, placed
    by pos and euler_deg (degrees, xyz) in its object's (or link's) frame; rgba: its own colour."""

    keys_label: ClassVar[str] = "a part key"

    shape: Literal[SHAPES] = None
    size: Sizes = None
    mesh: Any = None            # a file path or {file, scale}: sim/scene/mesh_files.py
    open_box: OpenBox = None
    open_cylinder: OpenCylinder = None
    pos: Point3 = [0.0, 0.0, 0.0]
    euler_deg: Vec3 = [0.0, 0.0, 0.0]
    rgba: Rgba = None

    @model_validator(mode="before")
    @classmethod
    def _one_kind(cls, raw):
        if isinstance(raw, dict):
            kinds = [k for k in PART_KINDS if k in raw]
            if len(kinds) != 1 or ("size" in raw) != ("shape" in raw):
                raise ValueError(f"exactly one of shape (with size, one of {list(SHAPES)}), mesh or a generated "
                                 f"shape {list(GENERATORS)}")
        return raw

    _size = field_validator("size")(shape_size)


class Joint(CatalogModel):
    """A link's joint: its axis in the link frame, range (radians for a hinge, metres for a slide), and
    MuJoCo's joint dynamics; `initial` is its value at the start of an episode."""

    keys_label: ClassVar[str] = "a joint key"

    type: Literal[JOINT_KINDS]
    axis: Vec3
    range: Vec2
    damping: NonNegativeNumber = 0.1
    stiffness: NonNegativeNumber = 0.0
    springref: Number = 0.0
    frictionloss: NonNegativeNumber = 0.0
    armature: NonNegativeNumber = DEFAULT_ARMATURE
    initial: Number = 0.0

    @field_validator("axis")
    @classmethod
    def _non_zero(cls, axis: list[float]) -> list[float]:
        if not any(axis):
            raise ValueError("a non-zero axis")
        return axis

    @field_validator("range")
    @classmethod
    def _increasing(cls, bounds: list[float]) -> list[float]:
        if not bounds[0] < bounds[1]:
            raise ValueError("[low, high] with low < high")
        return bounds

    @field_validator("initial")
    @classmethod
    def _within_range(cls, initial: float, info: ValidationInfo) -> float:
        bounds = info.data.get("range")
        if bounds is not None and not bounds[0] <= initial <= bounds[1]:
            raise ValueError(f"a value within the range [{bounds[0]}, {bounds[1]}]")
        return initial


class LinkBody(CatalogModel):
    """What a link and a row of keys share: the joint, the parts (link frame), the mass and colour."""

    euler_deg: Vec3 = [0.0, 0.0, 0.0]
    joint: Joint
    parts: list[PartEntry] = Field(min_length=1)
    mass: Mass
    rgba: Rgba = None


class Link(LinkBody):
    """A link on its joint; `pos` is the joint anchor (the link frame) in the object frame."""

    keys_label: ClassVar[str] = "a link key"

    pos: Point3 = [0.0, 0.0, 0.0]


class KeyRow(LinkBody):
    """A row of identical keys, one link each: the first at `origin`, each next one `pitch` further."""

    keys_label: ClassVar[str] = "a key row key"

    names: list[Name] = Field(min_length=1)
    origin: Point3
    pitch: Point3 = [0.0, 0.0, 0.0]


def unique_link_names(links: dict[str, Link] | None, key_rows: list[KeyRow] | None) -> None:
    """Links and keys become joints "<object>/<name>": their names are unique and have no '/'."""
    names = [*(links or {}), *(n for row in key_rows or [] for n in row.names)]
    bad = sorted({n for n in names if "/" in n or names.count(n) > 1})
    if bad:
        raise ValueError(f"link and key names that are unique and have no '/' ({bad} do not)")
