"""The `strike` step kind's schema."""

from __future__ import annotations

from typing import ClassVar

from pydantic import ValidationInfo, field_validator

from sim.scene.parts import parts_aabb

from ..base import Name
from .fields import ObjectPoint, PLAN_GRASPS, PlaceOffset, TABLE_TARGET, TaskObject, an_object, plan_scope
from .step import GraspFields, PlanStep


class StrikeStep(PlanStep, GraspFields):
    """{hand, strike, tool, strike_point, place, [place_offset], [grasp], [grasp_point], [grasp_yaw],
    [grasp_squeeze_m], [approach_pitch_deg], [after], [wait_s]}: pick the tool up (grasp fields as for `pick`), strike the
    target object once with the tool's strike_point (tool frame, on the tool), then put the tool onto or
    into `place` (an object, or `table` with place_offset a spot of the table top). grasp: flat_pinch takes a
    tool lying flat (a hammer by its handle, grasp_point near its balance point)."""

    grasps: ClassVar[tuple[str, ...]] = (*PLAN_GRASPS, "flat_pinch")
    part_pinch: ClassVar[bool] = True       # a pinch's grasp_point: where on the handle it closes

    strike: TaskObject
    tool: Name
    strike_point: ObjectPoint
    place: Name
    place_offset: PlaceOffset = None

    @field_validator("tool", mode="before")
    @classmethod
    def _a_tool(cls, name: str, info: ValidationInfo) -> str:
        return an_object(name, info, but=(info.data.get("strike"),))

    @field_validator("strike_point")
    @classmethod
    def _on_the_tool(cls, point: list[float], info: ValidationInfo) -> list[float]:
        tool = info.data.get("tool")
        if tool is None:
            return point
        lo, hi = parts_aabb(plan_scope(info).objects[tool].parts)
        if not all(a <= v <= b for v, a, b in zip(point, lo, hi)):
            raise ValueError(f"a point on the tool, within its bounding box from {[round(float(a), 3) for a in lo]} "
                             f"to {[round(float(b), 3) for b in hi]}")
        return point

    @field_validator("place", mode="before")
    @classmethod
    def _a_place(cls, place: str, info: ValidationInfo) -> str:
        return an_object(place, info, but=(info.data.get("tool"),), extra=(TABLE_TARGET,))
