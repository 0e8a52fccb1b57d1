"""The `handover` step kind's schema."""

from __future__ import annotations

from typing import ClassVar

from pydantic import Field, ValidationInfo, field_validator

from ..base import CatalogModel, Name, Number
from .fields import (AirPoint, GRASP_CLOSURE_RANGE, HANDS, ObjectPoint, PLACE_FROM_FRONT, PlaceFrom, RollDeg,
                     SIDE_GRASP, TaskObject, one_of, side_grasp_roll)
from .step import GraspFields, PlanStep


class BodyHold(CatalogModel):
    """A handover's `body_hold`: its take_point and take_roll_deg for an embodiment whose hand file declares
    `heavy_side_hold: body` (a hand that carries a heavy object round its body, not hooked round its edge)."""

    keys_label: ClassVar[str] = "a field of a body_hold"

    take_point: ObjectPoint = None
    take_roll_deg: RollDeg = None


class HandoverStep(PlanStep, GraspFields):
    """{hand, handover, to_hand, at, [pick_from], [take_point], [take_roll_deg], [grasp], [grasp_point],
    [grasp_roll_deg], [approach_pitch_deg], [grasp_yaw], [grasp_closure], [body_hold], [after], [wait_s]}: `hand`
    gives the object to `to_hand` in the air, its centre at `at` [x, y, z] (table top; z above it). A hand that does not
    hold it yet picks it first, as `pick` with the grasp fields (pick_from: front, with grasp: side, takes it
    out level through the side a container is open at, a bottle out of a fridge; grasp_closure closes a hand's
    declared tabletop grasp that many times as far from open: a bottle's neck, thinner than the fruit it is
    sized for). `to_hand` takes it from the other side with a side grasp at take_point (object frame, default
    its centre: clear of the giver's grasp_point), turned take_roll_deg about the fingers (as a side grasp's
    grasp_roll_deg, default 90: thumb up); body_hold {[take_point], [take_roll_deg]} replaces those two on an
    embodiment whose hand declares `heavy_side_hold: body`. The giver lets go and goes home. The next step of
    `to_hand` that names the object (a pour, a pick, a handover back) starts holding it."""

    grasps: ClassVar[tuple[str, ...]] = (SIDE_GRASP, "power")

    handover: TaskObject
    to_hand: Name
    at: AirPoint
    pick_from: PlaceFrom = "above"
    take_point: ObjectPoint = None
    take_roll_deg: RollDeg = None
    body_hold: BodyHold = None
    grasp_roll_deg: RollDeg = None
    # the Shadow's and the Wuji's tabletop grasps closed round a bottle's 3 cm neck without touching it
    grasp_closure: Number = Field(None, ge=GRASP_CLOSURE_RANGE[0], le=GRASP_CLOSURE_RANGE[1],
                                  description=f"a factor in [{GRASP_CLOSURE_RANGE[0]:g}, {GRASP_CLOSURE_RANGE[1]:g}]")

    @field_validator("to_hand", mode="before")
    @classmethod
    def _the_other_hand(cls, to_hand: str, info: ValidationInfo) -> str:
        others = [h for h in HANDS if h != info.data.get("hand")]
        return one_of(to_hand, others, " or ".join(map(repr, others)) + " (the other hand)")

    @field_validator("pick_from", mode="before")
    @classmethod
    def _front_with_a_side_grasp(cls, way: str, info: ValidationInfo) -> str:
        if way == PLACE_FROM_FRONT and info.data.get("grasp") != SIDE_GRASP:
            raise ValueError(f"pick_from: {PLACE_FROM_FRONT} only with grasp: {SIDE_GRASP} (the hand comes in level)")
        return way

    _side_only = field_validator("grasp_roll_deg", mode="before")(side_grasp_roll)
