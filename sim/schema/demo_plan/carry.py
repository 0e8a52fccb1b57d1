"""The `carry` step kind's schema."""

from __future__ import annotations

from typing import ClassVar

from pydantic import Field, ValidationInfo, field_validator

from ..base import Bool, Name, Number, is_number
from .fields import (BOTH_HANDS, PLACE_FROM_FRONT, PlaceFrom, PlaceOffset, SlideClearance, TOE_IN_RANGE_DEG,
                     TaskObject, an_object, front_container, plan_scope, slid_in)
from .step import PlanStep


class CarryStep(PlanStep):
    """{hand: both, carry, place, [place_from], [place_offset], [grasp_height], [toe_in_deg], [return_home],
    [approach_over], [after], [wait_s]}: both palms squeeze the object from opposite sides and carry it onto/into `place`
    (place_from and place_offset as for pick: with place_from: front it is slid in level through the
    side a container is open at, a bowl into a microwave); grasp_height (metres from its centre, within
    its half height) is where the palms press; toe_in_deg (default 10) how far each hand's fingers turn in
    towards the object about the vertical, which swings the forearms apart behind it; return_home: true
    sends both hands back to their home pose after letting go; approach_over: true brings each hand to the
    object over anything in its way, the place included (the other waits: they squeeze together);
    slide_clearance_m (place_from: front) is the object's bottom over the cavity floor as it slides in (default 4 cm)."""

    hands: ClassVar[tuple[str, ...]] = (BOTH_HANDS,)

    carry: TaskObject
    place_from: PlaceFrom = "above"         # before `place`, which it constrains
    place: Name
    place_offset: PlaceOffset = None
    grasp_height: Number = 0.0
    # the fingers turned in this far (degrees; default teleop/plan_steps/carry.py TOE_IN_DEG): the wrists
    # behind the palms further apart (two UR5 wrists met behind the cleaner at 10)
    toe_in_deg: Number = Field(None, ge=TOE_IN_RANGE_DEG[0], le=TOE_IN_RANGE_DEG[1],
                               description=f"degrees in [{TOE_IN_RANGE_DEG[0]:g}, {TOE_IN_RANGE_DEG[1]:g}]")
    return_home: Bool = False
    # each hand comes to the object over anything in its way, the place too (teleop/transit.py): straight from
    # home, a hand crossing to the far side of a ball swept the box it was to go in
    approach_over: Bool = False
    slide_clearance_m: SlideClearance = None
    _slid_in_only = field_validator("slide_clearance_m", mode="before")(slid_in)

    @field_validator("place", mode="before")
    @classmethod
    def _a_place(cls, place: str, info: ValidationInfo) -> str:
        if info.data.get("place_from") == PLACE_FROM_FRONT:
            return front_container(place, info, but=(info.data.get("carry"),))
        return an_object(place, info, but=(info.data.get("carry"),))

    @field_validator("grasp_height", mode="before")
    @classmethod
    def _within_its_height(cls, height: float, info: ValidationInfo) -> float:
        carried = info.data.get("carry")
        if carried is None:
            return height
        half_z = float(plan_scope(info).objects[carried].half_extents[2])
        if not is_number(height) or abs(height) > half_z:
            raise ValueError(f"metres from the object's centre in [{-half_z:g}, {half_z:g}]")
        return height
