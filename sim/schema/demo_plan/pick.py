"""The `pick` step kind's schema."""

from __future__ import annotations

import math
from typing import Any, ClassVar

from pydantic import Field, ValidationError, ValidationInfo, field_validator, model_validator

from ..base import Bool, Int, Name, Number, is_number
from .fields import (CARRY_RANGE_S, GRASP_YAW_ACROSS, LIFT_RANGE_M, OPEN_RANGE_S, ObjectAxis, ObjectPoint,
                     PICK_GRASPS, PLACE_FROM_FRONT, PRESS_RANGE_M, PlaceFrom, PlaceOffset, RollDeg, SIDE_GRASP,
                     SlideClearance, TABLE_TARGET, TaskObject, VIA_TIMES_RANGE, an_object, front_container,
                     only_with_grasp, side_grasp_roll, slid_in)
from .step import GraspFields, PlanStep, ViaStop


# what a pick's fallback may not change: what the step is (the hand, the object, its order in the plan)
FALLBACK_FIXED = frozenset({"hand", "pick", "after", "wait_s", "fallback"})


class PickStep(PlanStep, GraspFields):
    """{hand, pick, place, [place_offset], [place_from], [grasp], [approach_pitch_deg], [grasp_yaw],
    [grasp_point], [grasp_squeeze_m], [grasp_tips_height_m], [grasp_roll_deg], [after], [wait_s]}: carry an object onto or into `place` (an object,
    or `table` with place_offset the spot on the table top). place_from: front slides it in level through the side a
    container is open at (a microwave, a fridge shelf; place_offset's dz then from the cavity floor), its bottom
    slide_clearance_m over the cavity floor as it slides in (default 4 cm), and with slide_fingers_in: true the
    hand turned about the vertical on the way so that its fingers point straight in (the arm behind it through the
    mouth, not across the container's side); slide_as_held: true slides it in as it sits in the hand, the look
    outside the opening moving the slide for where it sits but not turning the hand to stand it as it stood (a
    banana lying on its side has no up: rolled in the grip, that turn pitched the hand).
    grasp_point is where a power grasp closes, or the part a pinch closes on (a bowl's rim), in the
    object's frame; pinch_fingers [index, middle, ...] are the fingers a pad pinch closes the thumb against
    (default the hand's own set, teleop/pinch_grasp.py), pinch_clear_tips: true spreads it until the fingertips,
    not only the pads, clear the part (a thin rim: teleop/pinch_tips.py); grasp: flat_pinch picks a thin object lying flat with the fingertips, either side of
    its centre or of grasp_point (a spatula's handle clear of its blade), grasp_squeeze_m (metres) aiming its
    closed tips that far past each other for a firmer hold (a heavy tool), grasp_tips_height_m (metres) bringing
    the hand down so its closed tips end that high over the object's bottom (half a handle's height), pinch_fold (a
    fraction) folding its other fingers that far towards their closed end instead of 0.9; grasp: side is the palm grasp
    from the side, thumb up, around an upright part (a drill's grip under its motor, a bottle), turned
    grasp_roll_deg about the fingers (default 90: thumb up). place_axis [x, y, z] (object frame) is turned
    on the way to point straight down and lowered that end first (a marker stood up in a pen cup; place_offset's
    dz then places that end); place_tilt_deg turns it that many degrees short of straight down, leaning (a thin
    pen slips out of a two-tip pinch as the turn nears vertical; the cup's wall stands it up as it drops in).
    via [{inside: <container>} | {over: <object>}, ...] takes the carried object's via_point through those
    stops, via_times rounds, on its way (a ladle into a pot, then over a bowl);
    hold: true keeps it in the hand over `place` (dz: its bottom above the table) for the hand's next pick
    of it (teleop/plan_steps/via.py). With grasp: flat_pinch, release_pinch_only: true lets go opening only the
    thumb and the pinching fingers (the folded ones stay), place_press_m (metres) sets it down that far below
    its release height, release_relax (a fraction) opens the thumb and the pinching fingers from where they
    hold that far towards the open hand, and place_yaw (degrees, world) picks, of the turns that set the object
    square to its target, the one with the tips closing (thumb to fingers) along it, and ease_turned: true turns the
    slide off the thumb's side with the hand as it is turned square (teleop/plan_steps/flat_place.py);
    grasp_yaw_object: true counts a flat pinch's grasp_yaw from the object's own x axis as it lies, not the world's.
    lift_m (metres) is how far the hand lifts the object over its grasp and carries it over the place (default 14 cm);
    carry_s (seconds) is how long the carry from the lift to above the place takes (default 1 s); open_s (seconds)
    how long the hand opens over the place before it rises (default 1/3 s: fingers wedged on the object open
    late, and the rising hand lifts it out). close_thumb_last:
    true closes a power grasp's thumb after its fingers, whatever the hand file's `late` (a small fruit pressed
    into the fingers' wall); thin_grasp: true closes a palm grasp to the hand file's targets for a thin object
    where it declares them (tabletop_grasp.thin_close: a 4 cm bottle that fingers eased for a wide jar would not
    reach; other hands close as without it); round_pinch: true (a pinch) takes a thin round object lying on the
    table (a pen, a battery) with the flat pinch its hand file declares for one (`round_pinch`: the fingers, how
    far the others fold, how high the tips close), other hands as the step's grasp; grasp_arm_clear: true (a flat
    pinch) turns the hand another way as good for the tips where the arm at the grasp runs into the scene;
    place_either_end: true (with place_axis) turns the other end down where turning place_axis down would run the
    hand into its own arm. return_home: true sends the hand back to its home pose once it has let go, rather than
    leaving it risen over the place (where the other arm reaches in next).
    fallback {field: value, ...} is the step done another way where the arm cannot do it as written
    (teleop/plan_steps/fallback.py): its IK, tracked along the step's planned wrist path, strays more than 10 cm
    from it (another branch), or a `place_axis` turn leaves an arm joint within 0.2 rad of its limit; those fields
    then replace the step's own (e.g. the other end down and a palm grasp)."""

    grasps: ClassVar[tuple[str, ...]] = PICK_GRASPS
    part_pinch: ClassVar[bool] = True

    pick: TaskObject
    place_from: PlaceFrom = "above"         # before `place`, which it constrains
    place: Name
    place_offset: PlaceOffset = None
    grasp_roll_deg: RollDeg = None
    place_axis: ObjectAxis = None           # turned on the way to point straight down (teleop/plan_steps/axis_place.py)
    place_tilt_deg: Number = Field(None, ge=0.0, le=60.0, description="degrees in [0, 60]")  # place_axis turned that far short of down
    # place_axis either end down: the other where this one turned down runs the hand into its own arm (axis_place.py)
    place_either_end: Bool = False
    hold: Bool = False                      # kept in the hand over `place` for its next step (plan_steps/via.py)
    from_plan: Bool = False                 # grasped where an earlier step leaves it (a drag), not where it lay
    via: list[ViaStop] = Field(None, min_length=1)  # waypoints on the way to `place`
    via_times: Int = Field(None, ge=VIA_TIMES_RANGE[0], le=VIA_TIMES_RANGE[1],
                           description=f"a whole number of rounds in [{VIA_TIMES_RANGE[0]}, {VIA_TIMES_RANGE[1]}]")
    via_point: ObjectPoint = None           # the carried object's point that goes through the stops (a ladle's bowl)
    # flat pinch, letting go: only the thumb and the pinching fingers open, the folded ones stay (plan_steps/flat_place.py)
    release_pinch_only: Bool = False
    place_press_m: Number = Field(None, ge=PRESS_RANGE_M[0], le=PRESS_RANGE_M[1],   # flat pinch: set down this far below
                                  description=f"metres in [{PRESS_RANGE_M[0]:g}, {PRESS_RANGE_M[1]:g}]")  # its release height
    # flat pinch: the pinching digits open from where they hold, this fraction of the way to open (not to the pre-shape)
    release_relax: Number = Field(None, gt=0.0, le=1.0, description="a fraction in (0, 1]")
    # palm grasp: the thumb closes after the fingers, whatever the hand file's `late` (plan_steps/pick_place.py)
    close_thumb_last: Bool = False
    # palm grasp: the hand file's targets for a thin object where it declares them (plan_steps/pick_place.py)
    thin_grasp: Bool = False
    # pinch: the hand file's flat pinch for a thin round object lying on the table where it declares one (a pen, a
    # battery; teleop/plan_steps/pick.py), else the step's grasp
    round_pinch: Bool = False
    # flat pinch: where the arm at the closed grasp runs into the scene (the UR5's wrist_1 link onto the pen cup),
    # another turn of the hand nearly as good for the tips that keeps it clear (teleop/plan_steps/pick_place.py)
    grasp_arm_clear: Bool = False
    # lifted this far over the grasp and carried this far over the place (default LIFT_HEIGHT_M, 14 cm): a lower
    # carry, less swing for a piece held by its edges (teleop/plan_steps/pick_place.py)
    lift_m: Number = Field(None, ge=LIFT_RANGE_M[0], le=LIFT_RANGE_M[1],
                           description=f"metres in [{LIFT_RANGE_M[0]:g}, {LIFT_RANGE_M[1]:g}]")
    # seconds the carry from the lift to above the place takes (default 1 s): a long reach, turning as it goes
    carry_s: Number = Field(None, gt=0.0, le=CARRY_RANGE_S[1], description=f"seconds in (0, {CARRY_RANGE_S[1]:g}]")
    # seconds the hand opens over the place before it rises (default DURATIONS["open"], 1/3 s)
    open_s: Number = Field(None, gt=0.0, le=OPEN_RANGE_S[1], description=f"seconds in (0, {OPEN_RANGE_S[1]:g}]")
    # flat pinch: of the turns that set the object square to its target, the one with the tips closing (thumb to
    # fingers) nearest this direction (degrees, world, from +x): the tips on the piece's free sides, off the target
    place_yaw: Number = Field(None, ge=-180.0, le=180.0, description="degrees in [-180, 180]")
    # flat pinch: the ease off the thumb's side turns with the hand as the operator's looks turn it square
    ease_turned: Bool = False
    # flat pinch: grasp_yaw counted from the object's own x axis as it lies, not from the world's +x (the hand
    # turns with the object: the tips meet its sides at the same angle however it was left turned)
    grasp_yaw_object: Bool = False
    # after letting go the hand goes back to its home pose, out of the other arm's way (teleop/plan_steps/pick.py)
    return_home: Bool = False
    # the step's fields done another way where the arm cannot do it as written (teleop/plan_steps/fallback.py)
    fallback: dict[str, Any] = None

    @model_validator(mode="after")
    def _fallback_a_pick(self, info: ValidationInfo):
        """`fallback` replaces some of the step's fields: the step with them must be a pick step too."""
        if self.fallback is None:
            return self
        fixed = sorted(FALLBACK_FIXED & set(self.fallback))
        if not self.fallback or fixed:
            raise ValueError(f"fallback: a non-empty mapping of pick fields other than {sorted(FALLBACK_FIXED)}")
        own = {k: getattr(self, k) for k in self.model_fields_set if k != "fallback"}
        try:
            type(self).model_validate({**own, **self.fallback}, context=info.context)
        except ValidationError as exc:
            first = exc.errors()[0]
            raise ValueError(f"fallback: {'.'.join(map(str, first['loc']))}: {first['msg']}") from None
        return self

    @field_validator("return_home", mode="before")
    @classmethod
    def _let_go_first(cls, back, info: ValidationInfo):
        if back is True and info.data.get("hold") is True:
            raise ValueError("no return_home: true with hold: true (the hand keeps the object over its place)")
        return back
    slide_clearance_m: SlideClearance = None
    _slid_in_only = field_validator("slide_clearance_m", mode="before")(slid_in)
    # place_from: front: the hand turned about the vertical on the way so its fingers point straight in
    slide_fingers_in: Bool = False
    _fingers_in_only = field_validator("slide_fingers_in", mode="before")(slid_in)
    # place_from: front: the look outside the opening moves the slide for where the object sits in the hand, but
    # does not turn the hand to stand it as it stood when picked (teleop/plan_steps/upright_look.py)
    slide_as_held: Bool = False
    _as_held_only = field_validator("slide_as_held", mode="before")(slid_in)

    @field_validator("hold", mode="before")
    @classmethod
    def _held_over_the_place(cls, hold, info: ValidationInfo):
        if hold is True and info.data.get("place_from") == PLACE_FROM_FRONT:
            raise ValueError(f"no hold: true with place_from: {PLACE_FROM_FRONT} (held over the place, not slid in)")
        return hold

    @field_validator("via")
    @classmethod
    def _not_through_itself(cls, via: list[ViaStop], info: ValidationInfo):
        picked = info.data.get("pick")
        for i, stop in enumerate(via):
            if picked in (stop.inside, stop.over):
                raise ValueError(f"stops at other objects than {picked!r}, the one carried (stop {i})")
        return via

    @field_validator("via_times", "via_point", mode="before")
    @classmethod
    def _only_with_via(cls, value, info: ValidationInfo):
        if info.data.get("via") is None:
            raise ValueError(f"no {info.field_name} without via (the stops it goes through)")
        return value

    _side_only = field_validator("grasp_roll_deg", mode="before")(side_grasp_roll)
    _power_only = field_validator("close_thumb_last", mode="before")(
        only_with_grasp("power", "the order a palm grasp closes in"))
    _palm_only = field_validator("thin_grasp", mode="before")(
        only_with_grasp(("power", SIDE_GRASP), "how far a palm grasp closes"))
    _pinch_only = field_validator("round_pinch", mode="before")(
        only_with_grasp(("pinch", "flat_pinch"), "the hand's pinch for a thin round object"))
    _flat_arm_clear = field_validator("grasp_arm_clear", mode="before")(
        only_with_grasp("flat_pinch", "the turn of a flat pinch's hand that keeps its arm clear"))
    _flat_place_only = field_validator("release_pinch_only", "place_press_m", "release_relax", "place_yaw",
                                       "ease_turned", mode="before")(
        only_with_grasp("flat_pinch", "how a flat pinch lets a thin object go"))
    _flat_pinch_turn = field_validator("grasp_yaw_object", mode="before")(
        only_with_grasp("flat_pinch", "where a flat pinch's grasp_yaw is counted from"))

    @model_validator(mode="after")
    def _yaw_to_count(self):
        if self.grasp_yaw_object and ("grasp_yaw" not in self.model_fields_set or self.grasp_yaw == GRASP_YAW_ACROSS):
            raise ValueError("grasp_yaw_object: true needs grasp_yaw in degrees (counted from the object's x axis)")
        return self

    @field_validator("place", mode="before")
    @classmethod
    def _a_place(cls, place: str, info: ValidationInfo) -> str:
        if info.data.get("place_from") == PLACE_FROM_FRONT:
            return front_container(place, info)
        return an_object(place, info, extra=(TABLE_TARGET,))

    @field_validator("place_yaw", mode="after")
    @classmethod
    def _squared_to_an_object(cls, yaw, info: ValidationInfo):
        if info.data.get("place") == TABLE_TARGET:
            raise ValueError(f"no place_yaw with place: {TABLE_TARGET} (set down as it is held, not squared to anything)")
        return yaw

    @field_validator("place_tilt_deg", "place_either_end", mode="before")
    @classmethod
    def _with_place_axis(cls, value, info: ValidationInfo):
        what = {"place_tilt_deg": "the axis it leaves leaning", "place_either_end": "the axis whose ends it chooses between"}
        if info.data.get("place_axis") is None:
            raise ValueError(f"no {info.field_name} without place_axis ({what[info.field_name]})")
        return value

    @field_validator("place_axis", mode="before")
    @classmethod
    def _an_axis_from_above(cls, axis, info: ValidationInfo):
        if info.data.get("place_from") == PLACE_FROM_FRONT:
            raise ValueError(f"no place_axis with place_from: {PLACE_FROM_FRONT} (slid in level, as held)")
        if isinstance(axis, list) and all(map(is_number, axis)) and math.hypot(*axis) < 1e-9:
            raise ValueError("a non-zero [x, y, z] in the object's frame")
        return axis
