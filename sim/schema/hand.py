"""Schema of `sim/catalog/hands/<name>.yaml` (conventions: sim/embodiment/description.py).

The `tactile` and `real_model` blocks have schemas of their own (sim/schema/tactile.py, real_model.py);
what they and the rest of the file refer to (links, joints, fingers, actuators) is checked by the loaders
(sim/embodiment/hand_file.py, tactile_block.py, real_model_file.py)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from .base import CatalogModel, Name, Number, PositiveNumber, Str, Vec3, ranged
from .demo_plan.fields import FOLD_RANGE, PINCH_FINGERS, TIPS_HEIGHT_RANGE_M
from .real_model import RealModel
from .robot_parts import (SPAN_M, Angle, Frame, GeomDefaults, Joint, JointDefaults, Length, LinkPair, Mass,
                          MassProperties, Point3)
from .tactile import TactileBlock


class Palm(MassProperties):
    name: Name


class FingerLink(MassProperties):
    name: Name
    origin: Frame | None = None          # without xyz: at the end of the previous link (its length along z)
    joints: list[Joint] = []
    length: Number = ranged(0.0, ge=0, le=SPAN_M, unit="m")
    radius: Length | None = None          # a capsule phalanx along +z, `length` long


class Finger(CatalogModel):
    name: Name
    parent: Name | None = None
    links: list[FingerLink] = Field(min_length=1)


class Actuator(CatalogModel):
    joint: Name
    name: Name | None = None
    effort: PositiveNumber | None = None
    velocity: PositiveNumber | None = None
    kp: Number | None = None
    kv: Number | None = None


class Coupling(CatalogModel):
    joint: Name      # follower
    master: Name
    polycoef: Annotated[list[Number], Field(min_length=1, max_length=5)]   # constant first


class GraspProbe(CatalogModel):
    radius: Length
    half_length: Length
    mass: Mass
    pos: Point3
    axis: Vec3 | None = None
    close: dict[str, Number]


class TabletopGrasp(CatalogModel):
    centre: Point3
    close: dict[str, Number]
    late: list[Name] = []
    thin_close: dict[str, Number] = {}      # a pick's thin_grasp: these actuators' targets instead (a thin bottle)


class RoundPinch(CatalogModel):
    """How the hand takes a thin round object lying on the table (a pen, a battery) where a pick asks for its
    `round_pinch`: a flat pinch of the thumb against `fingers`, the other fingers folded `fold` of the way
    (either left out: the hand's own flat pinch's; `{}` is the flat pinch as the hand makes it), and with
    `tips_height_m` its closed tips that high over the object's bottom rather than pressed onto the table."""

    fingers: Annotated[list[Literal[PINCH_FINGERS]], Field(min_length=1)] = None
    fold: Number = Field(None, ge=FOLD_RANGE[0], le=FOLD_RANGE[1],
                         description=f"a fraction in [{FOLD_RANGE[0]:g}, {FOLD_RANGE[1]:g}]")
    # the closed tips this high over the object's bottom (a step's grasp_tips_height_m), not pressed into the table
    tips_height_m: Number = Field(None, ge=TIPS_HEIGHT_RANGE_M[0], le=TIPS_HEIGHT_RANGE_M[1],
                                  description=f"metres in [{TIPS_HEIGHT_RANGE_M[0]:g}, {TIPS_HEIGHT_RANGE_M[1]:g}]")


# MediaPipe's fingertip landmarks (sim/embodiment/retarget_spec.py)
FINGERTIP_KEYPOINTS = ("thumb_tip", "index_tip", "middle_tip", "ring_tip", "pinky_tip")


class RobotPoint(CatalogModel):
    body: Name                      # a link of this hand (checked by the loader)
    pos: Point3 = [0.0, 0.0, 0.0]   # in the link frame


class Fingertip(RobotPoint):
    finger: Name
    keypoint: Literal[FINGERTIP_KEYPOINTS]


class Retarget(CatalogModel):
    """DexPilot retargeting: robot points that stand for the operator's wrist and fingertips."""

    scale: PositiveNumber           # robot / human hand size
    wrist: RobotPoint
    fingertips: list[Fingertip] = Field(description="a list with one entry per finger")


class HandFile(CatalogModel):
    name: Name | None = None
    display_name: Str | None = None
    source: Str
    assumptions: Str = ""
    mount: Frame | None = None
    palm: Palm
    fingers: list[Finger] = Field(min_length=1)
    actuators: list[Actuator] = Field(min_length=1)
    couplings: list[Coupling] | None = None
    wrist_site: Frame
    home: dict[str, Angle] | None = None
    grasp_probe: GraspProbe | None = None
    tabletop_grasp: TabletopGrasp | None = None
    # how the hand carries a heavy object taken from the side (a bottle handed over): "edge", its fingers
    # hooked round the object's end edge; "body", round its body at its mass centre (a handover's body_hold)
    heavy_side_hold: Literal["edge", "body"] = "edge"
    # a pick's `round_pinch: true` (a pen, a battery lying on the table) takes it with this flat pinch
    round_pinch: RoundPinch | None = None
    tactile: TactileBlock
    real_model: RealModel | None = None
    retarget: Retarget | None = None
    contact_exclude: list[LinkPair] | None = None
    servo_error_at_full_effort: PositiveNumber = 0.1
    joint_defaults: JointDefaults | None = None
    geom_defaults: GeomDefaults | None = None
