"""Schema of a hand file's `tactile` block and of one contact pad: keys, types, ranges, and what one pad
or one group says about itself (unit, orthogonal vectors). What looks across the block and the hand (a
site's finger and link, its group and pad, one site per finger, the grouping policy) is checked by
sim/embodiment/tactile_block.py once the block has passed this schema.
"""

from __future__ import annotations

from typing import ClassVar, Literal

import numpy as np
from pydantic import Field, ValidationInfo, field_validator

from .base import CatalogModel, Int, Name, NonNegativeNumber, PositiveInt, PositiveNumber, Vec3
from .robot_parts import PerSide

TACTILE_GROUPINGS = ("side_shared", "side_specific", "per_finger")
TACTILE_NORMAL_CONVENTIONS = ("inward", "outward")
PAD_CONDIMS = (1, 3, 4, 6)
DEFAULT_PAD_FRICTION = (1.2, 0.02, 0.002)
DEFAULT_PAD_CONDIM = 4
PAD_UNIT_TOLERANCE = 1e-3
PAD_ORTHOGONAL_TOLERANCE = 1e-3

class Pad(CatalogModel):
    """A contact pad in its attach-body frame (metres): the surface point `center`, the outward unit
    `normal`, the unit `axis` along the finger (orthogonal to normal), its `length` along the axis and
    `width` across, and `curvature_radius` rounding it across the width (0: flat)."""

    keys_label: ClassVar[str] = "a pad key"

    center: Vec3
    normal: Vec3
    axis: Vec3
    length: PositiveNumber = Field(description="a positive number (metres)")
    width: PositiveNumber = Field(description="a positive number (metres)")
    curvature_radius: NonNegativeNumber = Field(0.0, description="a number >= 0 (metres)")

    @field_validator("normal", "axis")
    @classmethod
    def _unit(cls, vec: list[float]) -> list[float]:
        if abs(np.linalg.norm(vec) - 1.0) > PAD_UNIT_TOLERANCE:
            raise ValueError("a unit vector")
        return vec

    @field_validator("axis")
    @classmethod
    def _across_the_normal(cls, axis: list[float], info: ValidationInfo) -> list[float]:
        normal = info.data.get("normal")
        if normal is not None and abs(float(np.dot(normal, axis))) > PAD_ORTHOGONAL_TOLERANCE:
            raise ValueError("a vector orthogonal to normal")
        return axis


class Group(CatalogModel):
    keys_label: ClassVar[str] = "a group key"

    assets: PerSide[Name]       # the surface asset on each hand (the same name on both under side_shared)
    pad: Pad


class Site(CatalogModel):
    """One tactile site: a finger's pad on a link of the hand, in a group (and carrying its pad)."""

    keys_label: ClassVar[str] = "a site key"

    name: Name
    finger: Name
    group: Name
    attach_body: Name
    pad: Pad = None


class TactileBlock(CatalogModel):
    keys_label: ClassVar[str] = "a tactile key"

    grouping: Literal[TACTILE_GROUPINGS]
    normal_convention: Literal[TACTILE_NORMAL_CONVENTIONS]
    resolution: PositiveInt
    groups: dict[str, Group] = Field(min_length=1, description="a mapping of group name -> {assets, pad}")
    sites: list[Site] = Field(min_length=1, description="a non-empty list of sites")
    pad_friction: Vec3 = list(DEFAULT_PAD_FRICTION)
    pad_condim: Int = DEFAULT_PAD_CONDIM        # MuJoCo's contact dimensionality of the pad geoms

    @field_validator("pad_condim")
    @classmethod
    def _a_condim(cls, condim: int) -> int:
        if condim not in PAD_CONDIMS:
            raise ValueError("one of " + ", ".join(map(str, PAD_CONDIMS[:-1])) + f" or {PAD_CONDIMS[-1]}")
        return condim
