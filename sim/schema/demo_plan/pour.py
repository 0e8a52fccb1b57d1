"""The `pour` step kind's schema."""

from __future__ import annotations

import math
from typing import ClassVar

from pydantic import Field, ValidationInfo, field_validator

from ..base import Bool, Name, Number
from .fields import (POUR_DEFAULT_GRASP, POUR_DEFAULT_TILT_DEG, POUR_GRASPS, POUR_TILT_RANGE_DEG, TableDirection,
                     TableSpot, one_of, plan_scope)
from .step import GraspFields, PlanStep


class PourStep(PlanStep, GraspFields):
    """{hand, pour, into, [tilt_deg], [tilt_toward], [grasp], [approach_pitch_deg], [grasp_yaw],
    [grasp_point], [place_offset], [hold], [after], [wait_s]}: tip a pourer (an object with a `mouth_axis`) over
    `into` (an object, or a task point: poured just above it), then set it down where it was or at
    place_offset [x, y] of the table top; tilt_toward [dx, dy] (table top) is the way the mouth tips,
    e.g. away from something the bottle's body would hit; grasp_yaw (degrees only: "across" is worked
    out for a hand closing from above) and grasp_point as for `pick` (e.g. a side grasp held above the
    middle, so that the thumb comes down beside a bottle's shoulder, not onto it). hold: true keeps it in
    the hand, upright over the target, for the hand's next step (a handover back); a bottle the hand holds
    already (handed over) is poured from the hand, not grasped again."""

    grasps: ClassVar[tuple[str, ...]] = POUR_GRASPS
    across: ClassVar[bool] = False

    pour: Name
    into: Name
    grasp: Name = POUR_DEFAULT_GRASP
    tilt_deg: Number = Field(POUR_DEFAULT_TILT_DEG, ge=POUR_TILT_RANGE_DEG[0], le=POUR_TILT_RANGE_DEG[1],
                             description=f"degrees in [{POUR_TILT_RANGE_DEG[0]:g}, {POUR_TILT_RANGE_DEG[1]:g}]")
    place_offset: TableSpot = None
    tilt_toward: TableDirection = None
    hold: Bool = False                      # kept in the hand, upright over the target, for a handover next

    @field_validator("tilt_toward")
    @classmethod
    def _a_direction(cls, direction: list[float] | None) -> list[float] | None:
        if direction is not None and math.hypot(*direction) < 1e-9:
            raise ValueError("a non-zero [dx, dy]")
        return direction

    @field_validator("pour", mode="before")
    @classmethod
    def _a_pourer(cls, name: str, info: ValidationInfo) -> str:
        pourers = sorted(n for n, o in plan_scope(info).objects.items() if o.mouth_axis is not None)
        return one_of(name, pourers, f"an object with a mouth_axis from {pourers}")

    @field_validator("into", mode="before")
    @classmethod
    def _a_target(cls, into: str, info: ValidationInfo) -> str:
        scope = plan_scope(info)
        others = sorted(n for n in scope.objects if n != info.data.get("pour"))
        return one_of(into, [*others, *scope.points], f"an object from {others} or a point from {sorted(scope.points)}")
