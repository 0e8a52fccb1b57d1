"""The `drag` step kind's schema."""

from __future__ import annotations

from pydantic import Field, ValidationInfo, field_validator

from ..base import Name, Number, is_number
from .fields import (DRAG_CONTACTS, DRAG_HOOK, DRAG_HOOK_DEPTH_M, DRAG_PALM, DRAG_PITCH_DEG, ZoneOffset,
                     container_names, one_of, plan_scope)
from .step import PlanStep


class DragStep(PlanStep):
    """{hand, drag, to_zone, [place_offset], [contact], [hook_depth], [pitch_deg], [hook_closure], [after],
    [wait_s]}: pull a container across the table until its centre is at place_offset [dx, dy] from the
    zone's centre, the curled fingertips hook_depth below its rim, the fingers pitch_deg down and curled
    hook_closure of the wall hook (a tall box tips when full curl lifts its wall: pull low, barely curled).
    contact: palm instead pushes it from behind with the flat hand on its edge, thumb up, just above the
    table (a mug slid under a tap: too narrow for curled fingers, and nothing of the hand above it)."""

    drag: Name
    to_zone: Name
    place_offset: ZoneOffset = None
    contact: Name = DRAG_HOOK               # before the hook's fields, which it rules out
    hook_depth: Number = DRAG_HOOK_DEPTH_M
    pitch_deg: Number = Field(DRAG_PITCH_DEG, ge=0.0, le=80.0, description="degrees in [0, 80]")
    hook_closure: Number = Field(1.0, gt=0.0, le=1.0, description="a fraction of the wall hook's curl in (0, 1]")

    @field_validator("drag", mode="before")
    @classmethod
    def _a_container(cls, name: str, info: ValidationInfo) -> str:
        containers = container_names(plan_scope(info))
        return one_of(name, containers, f"a container from {containers}")

    @field_validator("to_zone", mode="before")
    @classmethod
    def _a_zone(cls, zone: str, info: ValidationInfo) -> str:
        zones = sorted(plan_scope(info).zones)
        return one_of(zone, zones, f"a zone from {zones}")

    @field_validator("contact", mode="before")
    @classmethod
    def _a_contact(cls, contact: str) -> str:
        return one_of(contact, DRAG_CONTACTS, f"one of {list(DRAG_CONTACTS)}")

    @field_validator("hook_depth", "pitch_deg", "hook_closure", mode="before")
    @classmethod
    def _only_with_a_hook(cls, value, info: ValidationInfo):
        if info.data.get("contact") == DRAG_PALM:
            raise ValueError(f"no {info.field_name} with contact: {DRAG_PALM} (the fingers push, not hook)")
        return value

    @field_validator("hook_depth", mode="before")
    @classmethod
    def _below_the_rim(cls, depth: float, info: ValidationInfo) -> float:
        container = info.data.get("drag")
        if container is None:            # refused above already
            return depth
        height = 2 * plan_scope(info).objects[container].interior_half_extents[2]
        if not is_number(depth) or not 0.0 < depth < height:
            raise ValueError(f"metres below the rim in (0, {height:.3f})")
        return depth
