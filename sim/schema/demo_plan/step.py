"""What every step kind shares: the hand and ordering fields (`PlanStep`), the grasp fields of a
step that picks something up (`GraspFields`), and a pick's via stops."""

from __future__ import annotations

from typing import Annotated, ClassVar, Literal

from pydantic import Field, ValidationInfo, field_validator, model_validator

from ..base import Bool, CatalogModel, Int, Name, Number, is_number
from .fields import (APPROACH_PITCH_RANGE_DEG, FOLD_RANGE, GRASP_YAW_ACROSS, HANDS, ObjectPoint, PARK_OUT_RANGE_M,
                     PINCH_FINGERS, PLAN_GRASPS, PlaceOffset, SQUEEZE_RANGE_M, TIPS_HEIGHT_RANGE_M, VIA_KINDS,
                     WAIT_RANGE_S, an_object, container_names, one_of, only_with_grasp, plan_scope)


class ViaStop(CatalogModel):
    """One of a pick's `via` stops (teleop/plan_steps/via.py): {inside: <container>} takes the carried
    object's via point into the container's cavity, below its rim; {over: <object>} above the object, clear
    of its top. `offset` [dx, dy] or [dx, dy, dz] (metres, world) shifts the spot."""

    keys_label: ClassVar[str] = "a field of a via stop"

    inside: Name = None
    over: Name = None
    offset: PlaceOffset = None

    @model_validator(mode="before")
    @classmethod
    def _one_kind(cls, stop):
        if isinstance(stop, dict) and sum(kind in stop for kind in VIA_KINDS) != 1:
            raise ValueError("exactly one of inside: <container> or over: <object>")
        return stop

    @field_validator("inside", mode="before")
    @classmethod
    def _a_container(cls, name, info: ValidationInfo) -> str:
        containers = container_names(plan_scope(info))
        return one_of(name, containers, f"a container from {containers}")

    @field_validator("over", mode="before")
    @classmethod
    def _an_object(cls, name, info: ValidationInfo) -> str:
        return an_object(name, info)


class PlanStep(CatalogModel):
    """Fields every kind has: `hand`, `after` (earlier steps, by index, that end before this one starts;
    the two hands otherwise work at once), `wait_s` (seconds it waits after them, or after the start) and
    `park_out_m` (metres outward of its home, away from the other arm, where it waits and, after its last
    step, rests)."""

    keys_label: ClassVar[str] = "a field of this step kind"
    hands: ClassVar[tuple[str, ...]] = HANDS

    hand: Name
    after: list[Int] = []
    wait_s: Number = Field(0.0, ge=WAIT_RANGE_S[0], le=WAIT_RANGE_S[1], description=f"seconds in [{WAIT_RANGE_S[0]:g}, {WAIT_RANGE_S[1]:g}]")
    # metres: the hand waits for `after` (and rests after the step, if it is its last) that far outward of its
    # home, away from the other arm's (teleop/plan_steps/park.py); default 0: at home
    park_out_m: Number = Field(0.0, ge=PARK_OUT_RANGE_M[0], le=PARK_OUT_RANGE_M[1],
                               description=f"metres in [{PARK_OUT_RANGE_M[0]:g}, {PARK_OUT_RANGE_M[1]:g}]")

    @field_validator("hand", mode="before")
    @classmethod
    def _a_hand(cls, hand: str) -> str:
        return one_of(hand, cls.hands, " or ".join(map(repr, cls.hands)))

    @field_validator("after", mode="before")
    @classmethod
    def _earlier_steps(cls, after, info: ValidationInfo):
        index = info.context["index"]
        if not isinstance(after, list) or not all(isinstance(j, int) and not isinstance(j, bool) and 0 <= j < index
                                                  for j in after):
            raise ValueError(f"a list of earlier step indices (0..{index - 1})" if index else
                             "an empty list (the first step has no earlier steps)")
        return after


class GraspFields(CatalogModel):
    """How a step that picks something up holds it. `grasp` comes before the fields that depend on it."""

    grasps: ClassVar[tuple[str, ...]] = PLAN_GRASPS
    across: ClassVar[bool] = True          # grasp_yaw may be "across" (worked out for a hand closing from above)
    part_pinch: ClassVar[bool] = False     # a pinch may take a grasp_point: the part it closes on (a rim, a handle)

    grasp: Name = "power"
    approach_pitch_deg: Number = Field(0.0, ge=APPROACH_PITCH_RANGE_DEG[0], le=APPROACH_PITCH_RANGE_DEG[1],
                                       description=f"degrees in [{APPROACH_PITCH_RANGE_DEG[0]:g}, "
                                                   f"{APPROACH_PITCH_RANGE_DEG[1]:g}]")
    grasp_yaw: Number | Literal["across"] = 0.0     # checked whole by _yaw
    grasp_point: ObjectPoint = None
    # a pad pinch's fingers against the thumb, or a flat pinch's tips' (default the hand's own choice: teleop/pinch_grasp.py)
    pinch_fingers: Annotated[list[Literal[PINCH_FINGERS]], Field(min_length=1)] = None
    # a flat pinch's closed tips aimed this far past each other: a firmer hold (teleop/pinch_squeeze.py)
    grasp_squeeze_m: Number = Field(None, ge=SQUEEZE_RANGE_M[0], le=SQUEEZE_RANGE_M[1],
                                    description=f"metres in [{SQUEEZE_RANGE_M[0]:g}, {SQUEEZE_RANGE_M[1]:g}]")
    # a flat pinch's closed tips this high over the object's bottom (the hand pressed no deeper into the table than
    # by default), e.g. half a handle's height, rather than the hand's lowest point pressed into the table
    grasp_tips_height_m: Number = Field(None, ge=TIPS_HEIGHT_RANGE_M[0], le=TIPS_HEIGHT_RANGE_M[1],
                                        description=f"metres in [{TIPS_HEIGHT_RANGE_M[0]:g}, {TIPS_HEIGHT_RANGE_M[1]:g}]")
    # a pad pinch's pre-shape spread until its fingertips, not only its pads, clear the part (curled fingertips
    # that reach past the pads land on a thin rim otherwise; teleop/pinch_tips.py)
    pinch_clear_tips: Bool = False
    # a flat pinch's other fingers (not pinching) folded this fraction of the way to their closed end (default 0.9,
    # teleop/pinch_grasp.py): folded that far, the DexHand021's pressed a jigsaw piece's top and turned it over
    pinch_fold: Number = Field(None, ge=FOLD_RANGE[0], le=FOLD_RANGE[1],
                               description=f"a fraction in [{FOLD_RANGE[0]:g}, {FOLD_RANGE[1]:g}]")

    @field_validator("grasp", mode="before")
    @classmethod
    def _a_grasp(cls, grasp: str) -> str:
        return one_of(grasp, cls.grasps, f"one of {list(cls.grasps)}")

    @field_validator("approach_pitch_deg", mode="before")
    @classmethod
    def _not_with_flat_pinch(cls, pitch: float, info: ValidationInfo) -> float:
        if info.data.get("grasp") == "flat_pinch":
            raise ValueError("no approach_pitch_deg with grasp: flat_pinch (the hand turns its fingertips down to "
                             "the table itself)")
        return pitch

    @field_validator("grasp_yaw", mode="before")
    @classmethod
    def _yaw(cls, yaw):
        words = f"{GRASP_YAW_ACROSS!r} or degrees in [-180, 180]" if cls.across else "degrees in [-180, 180]"
        if yaw == GRASP_YAW_ACROSS and cls.across:
            return yaw
        if not is_number(yaw) or not -180.0 <= yaw <= 180.0:
            raise ValueError(words)
        return yaw

    _a_pinch_only = field_validator("pinch_fingers", mode="before")(
        only_with_grasp(("pinch", "flat_pinch"), "the fingers the thumb closes against"))
    _flat_pinch_only = field_validator("grasp_squeeze_m", mode="before")(
        only_with_grasp("flat_pinch", "it presses the pinch's tips past each other"))
    _flat_pinch_tips_height = field_validator("grasp_tips_height_m", mode="before")(
        only_with_grasp("flat_pinch", "where a flat pinch's closed tips end on the part"))
    _flat_pinch_fold = field_validator("pinch_fold", mode="before")(
        only_with_grasp("flat_pinch", "how far a flat pinch's other fingers fold"))
    _pad_pinch_clear_tips = field_validator("pinch_clear_tips", mode="before")(
        only_with_grasp("pinch", "a pad pinch's pre-shape spread until its fingertips clear the part"))

    @field_validator("pinch_fingers")
    @classmethod
    def _distinct_fingers(cls, fingers: list[str]) -> list[str]:
        if len(set(fingers)) != len(fingers):
            raise ValueError(f"distinct fingers from {list(PINCH_FINGERS)}")
        return fingers

    @field_validator("grasp_point", mode="before")
    @classmethod
    def _not_with_a_pinch(cls, point, info: ValidationInfo):
        grasp = info.data.get("grasp")
        if grasp in ("pinch", "flat_pinch") and not cls.part_pinch:
            raise ValueError(f"no grasp_point with grasp: {grasp} (the pinch finds its own)")
        return point
