"""Schema of `sim/catalog/arms/<name>.yaml` (conventions: sim/embodiment/description.py)."""

from __future__ import annotations

from pydantic import Field, field_validator

from .base import Bool, CatalogModel, Name, PositiveNumber, Str, Vec4
from .robot_parts import Angle, Frame, GeomDefaults, Joint, JointDefaults, Length, LinkPair, MassProperties


class ArmBase(MassProperties):
    link: Name


class ArmLink(MassProperties):
    name: Name
    # shorthand: a capsule of this radius to the next joint (or the flange) plus a joint housing
    segment_radius: Length | None = None
    no_segment: Bool = False
    housing_half_length: Length | None = None
    housing_rgba: Vec4 | None = None


class ChainEntry(Joint):
    origin: Frame
    link: ArmLink


class Sides(CatalogModel):
    left: list[Angle]
    right: list[Angle]


class Reach(CatalogModel):
    home_radius_m: Length      # measured with `python -m sim.embodiment.reach`


class ArmFile(CatalogModel):
    name: Name | None = None
    display_name: Str | None = None
    source: Str
    approximations: Str = ""
    base: ArmBase
    chain: list[ChainEntry] = Field(min_length=1)
    flange: Frame
    # one angle per joint of the chain (checked by the loader), for both sides or per side
    home_seed: Sides = Field(description="a list of joint angles, or one per side {left, right}")
    servo_error_at_full_effort: PositiveNumber = 0.05
    contact_exclude: list[LinkPair] | None = None
    reach: Reach
    ik_keep_sign: list[Name] | None = Field(None, description="a list of joint names")
    joint_defaults: JointDefaults | None = None
    geom_defaults: GeomDefaults | None = None

    @field_validator("home_seed", mode="before")
    @classmethod
    def _both_sides(cls, value):
        return {"left": value, "right": value} if isinstance(value, list) else value
