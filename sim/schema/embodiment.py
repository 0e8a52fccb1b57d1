"""Schema of `sim/catalog/embodiments/<name>.yaml`: an arm and a hand file, mounted twice, with cameras."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from .base import CatalogModel, Name, Number, Str, ranged
from .robot_parts import Angle, Frame, Length, Point3

CAMERA_NAMES = ("chest", "overhead", "stereo_left", "stereo_right", "left_wrist", "right_wrist")
SIDES = ("left", "right")


class SideFrames(CatalogModel):
    left: Frame
    right: Frame


class SideVectors(CatalogModel):
    left: list[Angle]
    right: list[Angle]


class Home(CatalogModel):
    right_wrist: Frame                 # the right wrist site's home pose in the world (left mirrored)
    arm: SideVectors | None = None     # explicit arm joint angles per side
    seed: SideVectors | None = None    # IK seeds per side (else the arm file's)


class Camera(CatalogModel):
    fovy: Number | None = ranged(None, gt=0, lt=180)
    pos: Point3 | None = None
    target: Point3 | None = None


class Torso(CatalogModel):
    pos: Point3 | None = None
    size: list[Length] | None = Field(None, min_length=3, max_length=3)


class EmbodimentFile(CatalogModel):
    name: Name | None = None
    display_name: Str
    arm: Name
    hand: Name
    mount: SideFrames
    home: Home
    cameras: dict[Literal[CAMERA_NAMES], Camera | None] | None = None
    torso: Torso | None = None
    tactile_attach: dict[str, Name] | None = None   # tactile site -> hand link holding it
