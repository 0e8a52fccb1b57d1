"""Schema of a task's `demo_plan` steps: one model per step kind (sim/demo_plan.py picks the kind).

Shapes, types and ranges are declared on the fields. What a step names in its task (an object, a
container, a hinge and its range, a pourer, a task point) is checked by field validators against the
`PlanScope` passed as validation context; a validator that needs another field reads it from the fields
validated before it, so field order matters where noted. Errors name the field (`demo_plan[2].place`)
and what was expected, through the schema layer's messages (sim/schema/messages.py).
An optional field absent from the step takes its planner's default: `= None` here means "absent" (a
default is not validated), so an explicit null in the file is refused by the field's type.
"""

from __future__ import annotations

import math
from typing import Annotated, ClassVar, Literal

from pydantic import BeforeValidator, Field, ValidationInfo, field_validator, model_validator

from sim.scene.parts import parts_aabb

from .base import Bool, CatalogModel, Int, Name, Number, is_number

TABLE_TARGET = "table"      # place: table puts an object down at place_offset [x, y] of the table top (centre 0, 0)
HANDS = ("left", "right")
BOTH_HANDS = "both"         # `hand: both`: a step of both hands at once (carry)
PLAN_GRASPS = ("power", "pinch")
SIDE_GRASP = "side"         # the hand's palm grasp turned to the side, thumb up: a tall object (a bottle, a drill's grip)
PICK_GRASPS = (*PLAN_GRASPS, "flat_pinch", SIDE_GRASP)   # flat_pinch: the fingertips to the table beside a thin object lying flat
GRASP_YAW_ACROSS = "across"   # grasp_yaw: the hand turned to close across the object's narrow side
PINCH_FINGERS = ("index", "middle", "ring", "little")   # pinch_fingers: what a pad pinch's thumb may close against
PLACE_FROM_FRONT = "front"
PLACE_FROM = ("above", PLACE_FROM_FRONT)   # lowered from above, or slid in through a side opening
WAIT_RANGE_S = (0.0, 60.0)
APPROACH_PITCH_RANGE_DEG = (0.0, 80.0)
DRAG_HOOK_DEPTH_M = 0.02    # drag: curled fingertips this far below the container's rim
DRAG_PITCH_DEG = 20.0       # ... the fingers tilted this far down into it
DRAG_HOOK, DRAG_PALM = "hook", "palm"   # drag's contact: fingers hooked inside its wall, or pushing it from behind
DRAG_CONTACTS = (DRAG_HOOK, DRAG_PALM)
POUR_TILT_RANGE_DEG = (50.0, 150.0)   # mouth axis from vertical: a pour threshold .. near upside down
POUR_DEFAULT_TILT_DEG = 85.0          # a person's pour: the bottle near horizontal, well past 50
SIDE_ROLL_RANGE_DEG = (60.0, 135.0)   # grasp_roll_deg of a side grasp: 90 thumb up, more: the palm turned partly up
POUR_GRASPS = (SIDE_GRASP, *PLAN_GRASPS)  # side: palm against a tall bottle, thumb up (a person's hold)
POUR_DEFAULT_GRASP = SIDE_GRASP
TURN_SPEED_RANGE_M_S = (0.0, 0.3)    # turn's speed: the contact along the arc, above 0 and at most a brisk swing
VIA_KINDS = ("inside", "over")      # a pick's via stops: into a container's cavity, below its rim; above an object
VIA_TIMES_RANGE = (1, 10)
PRESS_RANGE_M = (0.0, 0.03)      # place_press_m: a flat pinch's object set down up to 3 cm below its release height
SQUEEZE_RANGE_M = (0.0, 0.05)   # grasp_squeeze_m: a flat pinch's tips aimed past each other, up to 5 cm
TIPS_HEIGHT_RANGE_M = (0.0, 0.03)   # grasp_tips_height_m: a flat pinch's closed tips up to 3 cm over the object's bottom
CARRY_RANGE_S = (0.0, 10.0)     # carry_s: a pick's carry, above 0 and at most 10 s
OPEN_RANGE_S = (0.0, 3.0)       # open_s: a pick's hand opening over its place before it rises, above 0 and at most 3 s
TOE_IN_RANGE_DEG = (0.0, 30.0)  # toe_in_deg: a carry's fingers turned in towards the object, level .. 30 degrees
SLIDE_CLEARANCE_RANGE_M = (0.0, 0.15)   # slide_clearance_m: a front place's object bottom over the cavity floor


# place_from: front: the object's bottom this far above the cavity floor as it slides in (default 4 cm)
SlideClearance = Annotated[Number, Field(ge=SLIDE_CLEARANCE_RANGE_M[0], le=SLIDE_CLEARANCE_RANGE_M[1],
                                         description=f"metres in [{SLIDE_CLEARANCE_RANGE_M[0]:g}, "
                                                     f"{SLIDE_CLEARANCE_RANGE_M[1]:g}]")]


def _slid_in(value, info: ValidationInfo):
    """slide_clearance_m, slide_fingers_in only with place_from: front (nothing slides in otherwise)."""
    if info.data.get("place_from") != PLACE_FROM_FRONT:
        raise ValueError(f"no {info.field_name} without place_from: {PLACE_FROM_FRONT} (nothing slides in)")
    return value


def _vector(lengths: tuple[int, ...], words: str):
    """A list of finite numbers of one of these lengths; anything else is refused in ``words`` as a whole."""
    def check(value):
        if not isinstance(value, list) or len(value) not in lengths or not all(map(is_number, value)):
            raise ValueError(words)
        return value
    return Annotated[list[Number], BeforeValidator(check)]


PlaceOffset = _vector((2, 3), "[dx, dy] or [dx, dy, dz] in metres")
TableSpot = _vector((2,), "[x, y] of the table top in metres")
TableDirection = _vector((2,), "[dx, dy], a direction on the table top")
ZoneOffset = _vector((2,), "[dx, dy] from the zone's centre in metres")
ObjectPoint = _vector((3,), "[x, y, z] in the object's frame, metres")
ObjectAxis = _vector((3,), "[x, y, z], a direction in the object's frame")
AirPoint = _vector((3,), "[x, y, z] of the table top in metres, z above it")


def _only_with_grasp(grasp: str, what: str):
    """A `before` check of a field that means something with one grasp only (``what`` it is): refused with
    any other grasp (the step's `grasp` is validated before it)."""
    def check(value, info: ValidationInfo):
        if info.data.get("grasp") != grasp:
            raise ValueError(f"no {info.field_name} without grasp: {grasp} ({what})")
        return value
    return check


_side_grasp_roll = _only_with_grasp(SIDE_GRASP, "the hand's turn about its fingers")
# a side grasp's turn about the fingers (grasp_roll_deg, take_roll_deg)
RollDeg = Annotated[Number, Field(ge=SIDE_ROLL_RANGE_DEG[0], le=SIDE_ROLL_RANGE_DEG[1],
                                  description=f"degrees in [{SIDE_ROLL_RANGE_DEG[0]:g}, {SIDE_ROLL_RANGE_DEG[1]:g}]")]


def _scope(info: ValidationInfo):
    return info.context["scope"]


def _containers(scope) -> list[str]:
    return sorted(n for n, o in scope.objects.items() if o.interior_half_extents is not None)


def _one_of(value, names, expected: str) -> str:
    """`value` if it is one of `names` (checked before the field's type: anything else gets `expected`)."""
    if not isinstance(value, str) or value not in list(names):
        raise ValueError(expected)
    return value


def _object(value: str, info: ValidationInfo, *, but: tuple = (), extra: tuple = ()) -> str:
    """An object of the task's (not one of ``but``), or one of the ``extra`` words."""
    names = sorted(n for n in _scope(info).objects if n not in but)
    also = "".join(f" or {e!r}" for e in extra)
    return _one_of(value, [*names, *extra], f"an object from {names}{also}")


# a field naming one of the task's objects
TaskObject = Annotated[Name, BeforeValidator(lambda name, info: _object(name, info))]
# place_from: lowered from above, or slid in level through the side a container is open at
PlaceFrom = Annotated[Name, BeforeValidator(lambda way: _one_of(way, PLACE_FROM, f"one of {list(PLACE_FROM)}"))]


def _front_container(place: str, info: ValidationInfo, *, but: tuple = ()) -> str:
    """`place` with place_from: front: one of the task's containers (not one of ``but``)."""
    containers = [c for c in _containers(_scope(info)) if c not in but]
    return _one_of(place, containers, f"with place_from: front, a container from {containers}")


def _hinges(info: ValidationInfo) -> dict:
    return {f"{n}/{link.name}": link.joint.range for n, o in _scope(info).objects.items() for link in o.links
            if link.joint.type == "hinge"}


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
        containers = _containers(_scope(info))
        return _one_of(name, containers, f"a container from {containers}")

    @field_validator("over", mode="before")
    @classmethod
    def _an_object(cls, name, info: ValidationInfo) -> str:
        return _object(name, info)


class PlanStep(CatalogModel):
    """Fields every kind has: `hand`, `after` (earlier steps, by index, that end before this one starts;
    the two hands otherwise work at once) and `wait_s` (seconds it waits after them, or after the start)."""

    keys_label: ClassVar[str] = "a field of this step kind"
    hands: ClassVar[tuple[str, ...]] = HANDS

    hand: Name
    after: list[Int] = []
    wait_s: Number = Field(0.0, ge=WAIT_RANGE_S[0], le=WAIT_RANGE_S[1], description=f"seconds in [{WAIT_RANGE_S[0]:g}, {WAIT_RANGE_S[1]:g}]")

    @field_validator("hand", mode="before")
    @classmethod
    def _a_hand(cls, hand: str) -> str:
        return _one_of(hand, cls.hands, " or ".join(map(repr, cls.hands)))

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

    @field_validator("grasp", mode="before")
    @classmethod
    def _a_grasp(cls, grasp: str) -> str:
        return _one_of(grasp, cls.grasps, f"one of {list(cls.grasps)}")

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

    @field_validator("pinch_fingers", mode="before")
    @classmethod
    def _a_pinch_only(cls, fingers, info: ValidationInfo):
        if info.data.get("grasp") not in ("pinch", "flat_pinch"):
            raise ValueError("no pinch_fingers without grasp: pinch or flat_pinch (the fingers the thumb closes against)")
        return fingers
    _flat_pinch_only = field_validator("grasp_squeeze_m", mode="before")(
        _only_with_grasp("flat_pinch", "it presses the pinch's tips past each other"))
    _flat_pinch_tips_height = field_validator("grasp_tips_height_m", mode="before")(
        _only_with_grasp("flat_pinch", "where a flat pinch's closed tips end on the part"))
    _pad_pinch_clear_tips = field_validator("pinch_clear_tips", mode="before")(
        _only_with_grasp("pinch", "a pad pinch's pre-shape spread until its fingertips clear the part"))

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


class PickStep(PlanStep, GraspFields):
    """{hand, pick, place, [place_offset], [place_from], [grasp], [approach_pitch_deg], [grasp_yaw],
    [grasp_point], [grasp_squeeze_m], [grasp_tips_height_m], [grasp_roll_deg], [after], [wait_s]}: carry an object onto or into `place` (an object,
    or `table` with place_offset the spot on the table top). place_from: front slides it in level through the side a
    container is open at (a microwave, a fridge shelf; place_offset's dz then from the cavity floor), its bottom
    slide_clearance_m over the cavity floor as it slides in (default 4 cm), and with slide_fingers_in: true the
    hand turned about the vertical on the way so that its fingers point straight in (the arm behind it through the
    mouth, not across the container's side).
    grasp_point is where a power grasp closes, or the part a pinch closes on (a bowl's rim), in the
    object's frame; pinch_fingers [index, middle, ...] are the fingers a pad pinch closes the thumb against
    (default the hand's own set, teleop/pinch_grasp.py), pinch_clear_tips: true spreads it until the fingertips,
    not only the pads, clear the part (a thin rim: teleop/pinch_tips.py); grasp: flat_pinch picks a thin object lying flat with the fingertips, either side of
    its centre or of grasp_point (a spatula's handle clear of its blade), grasp_squeeze_m (metres) aiming its
    closed tips that far past each other for a firmer hold (a heavy tool), grasp_tips_height_m (metres) bringing
    the hand down so its closed tips end that high over the object's bottom (half a handle's height); grasp: side is the palm grasp
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
    carry_s (seconds) is how long the carry from the lift to above the place takes (default 1 s); open_s (seconds)
    how long the hand opens over the place before it rises (default 1/3 s: fingers wedged on the object open
    late, and the rising hand lifts it out). close_thumb_last:
    true closes a power grasp's thumb after its fingers, whatever the hand file's `late` (a small fruit pressed
    into the fingers' wall). return_home: true sends the hand back to its home pose once it has let go, rather
    than leaving it risen over the place (where the other arm reaches in next)."""

    grasps: ClassVar[tuple[str, ...]] = PICK_GRASPS
    part_pinch: ClassVar[bool] = True

    pick: TaskObject
    place_from: PlaceFrom = "above"         # before `place`, which it constrains
    place: Name
    place_offset: PlaceOffset = None
    grasp_roll_deg: RollDeg = None
    place_axis: ObjectAxis = None           # turned on the way to point straight down (teleop/plan_steps/axis_place.py)
    place_tilt_deg: Number = Field(None, ge=0.0, le=60.0, description="degrees in [0, 60]")  # place_axis turned that far short of down
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

    @field_validator("return_home", mode="before")
    @classmethod
    def _let_go_first(cls, back, info: ValidationInfo):
        if back is True and info.data.get("hold") is True:
            raise ValueError("no return_home: true with hold: true (the hand keeps the object over its place)")
        return back
    slide_clearance_m: SlideClearance = None
    _slid_in_only = field_validator("slide_clearance_m", mode="before")(_slid_in)
    # place_from: front: the hand turned about the vertical on the way so its fingers point straight in
    slide_fingers_in: Bool = False
    _fingers_in_only = field_validator("slide_fingers_in", mode="before")(_slid_in)

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

    _side_only = field_validator("grasp_roll_deg", mode="before")(_side_grasp_roll)
    _power_only = field_validator("close_thumb_last", mode="before")(
        _only_with_grasp("power", "the order a palm grasp closes in"))
    _flat_place_only = field_validator("release_pinch_only", "place_press_m", "release_relax", "place_yaw",
                                       "ease_turned", mode="before")(
        _only_with_grasp("flat_pinch", "how a flat pinch lets a thin object go"))
    _flat_pinch_turn = field_validator("grasp_yaw_object", mode="before")(
        _only_with_grasp("flat_pinch", "where a flat pinch's grasp_yaw is counted from"))

    @model_validator(mode="after")
    def _yaw_to_count(self):
        if self.grasp_yaw_object and ("grasp_yaw" not in self.model_fields_set or self.grasp_yaw == GRASP_YAW_ACROSS):
            raise ValueError("grasp_yaw_object: true needs grasp_yaw in degrees (counted from the object's x axis)")
        return self

    @field_validator("place", mode="before")
    @classmethod
    def _a_place(cls, place: str, info: ValidationInfo) -> str:
        if info.data.get("place_from") == PLACE_FROM_FRONT:
            return _front_container(place, info)
        return _object(place, info, extra=(TABLE_TARGET,))

    @field_validator("place_yaw", mode="after")
    @classmethod
    def _squared_to_an_object(cls, yaw, info: ValidationInfo):
        if info.data.get("place") == TABLE_TARGET:
            raise ValueError(f"no place_yaw with place: {TABLE_TARGET} (set down as it is held, not squared to anything)")
        return yaw

    @field_validator("place_tilt_deg", mode="before")
    @classmethod
    def _with_place_axis(cls, tilt, info: ValidationInfo):
        if info.data.get("place_axis") is None:
            raise ValueError("no place_tilt_deg without place_axis (the axis it leaves leaning)")
        return tilt

    @field_validator("place_axis", mode="before")
    @classmethod
    def _an_axis_from_above(cls, axis, info: ValidationInfo):
        if info.data.get("place_from") == PLACE_FROM_FRONT:
            raise ValueError(f"no place_axis with place_from: {PLACE_FROM_FRONT} (slid in level, as held)")
        if isinstance(axis, list) and all(map(is_number, axis)) and math.hypot(*axis) < 1e-9:
            raise ValueError("a non-zero [x, y, z] in the object's frame")
        return axis


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
        containers = _containers(_scope(info))
        return _one_of(name, containers, f"a container from {containers}")

    @field_validator("to_zone", mode="before")
    @classmethod
    def _a_zone(cls, zone: str, info: ValidationInfo) -> str:
        zones = sorted(_scope(info).zones)
        return _one_of(zone, zones, f"a zone from {zones}")

    @field_validator("contact", mode="before")
    @classmethod
    def _a_contact(cls, contact: str) -> str:
        return _one_of(contact, DRAG_CONTACTS, f"one of {list(DRAG_CONTACTS)}")

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
        height = 2 * _scope(info).objects[container].interior_half_extents[2]
        if not is_number(depth) or not 0.0 < depth < height:
            raise ValueError(f"metres below the rim in (0, {height:.3f})")
        return depth


class PressStep(PlanStep):
    """{hand, press: [<object>/<link>, ...], [after], [wait_s]}: press these slide-jointed links (keys,
    buttons) in order."""

    press: Annotated[list[Name], Field(min_length=1)]

    @field_validator("press", mode="before")
    @classmethod
    def _keys(cls, press, info: ValidationInfo):
        keys = sorted(f"{n}/{link.name}" for n, o in _scope(info).objects.items() for link in o.links
                      if link.joint.type == "slide")
        if not isinstance(press, list) or not press or not all(isinstance(k, str) and k in keys for k in press):
            raise ValueError(f"a non-empty list of slide-jointed links from {keys}")
        return press


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
        pourers = sorted(n for n, o in _scope(info).objects.items() if o.mouth_axis is not None)
        return _one_of(name, pourers, f"an object with a mouth_axis from {pourers}")

    @field_validator("into", mode="before")
    @classmethod
    def _a_target(cls, into: str, info: ValidationInfo) -> str:
        scope = _scope(info)
        others = sorted(n for n in scope.objects if n != info.data.get("pour"))
        return _one_of(into, [*others, *scope.points], f"an object from {others} or a point from {sorted(scope.points)}")


class TurnStep(PlanStep):
    """{hand, turn: <object>/<link>, to: <angle, rad>, [palm_from], [palm_look], [start_look], [speed], [return_home],
    [approach_over], [withdraw_past_end], [after], [wait_s]}: swing a
    hinge-jointed link (a lid, a door) to an angle within its joint range; from the link angle palm_from
    on (rad, within the range) the flat palm pushes, fingers along the hinge, instead of the fingertips;
    palm_look: true (with palm_from) re-aims the palm at the link's angle as the fingertips let go of it;
    start_look: true starts the turn from the link's angle as the hand sets off and as it comes down to it (planned
    from where earlier steps leave it): its keyframes turn about the hinge to it;
    speed (m/s) is how fast the hand's contact moves along the arc (default 0.09); return_home: false leaves
    the hand risen off the link where it let go, so the next step sets off from there; approach_over: true
    brings the hand to the link from above its top; withdraw_past_end: true takes the hand, once it lets go,
    out along the link past its free end before it goes on (round that end, not over the link: with home on the
    link's other side, round the end to that side first)."""

    turn: Name
    to: Number
    palm_from: Number = None
    # true: as the palm takes over, the operator looks where the link is (let go, it falls back) and pushes it from there
    palm_look: Bool = False
    # true: the turn starts from where the link is as the hand sets off for it, not where earlier steps meant to
    # leave it (a lever that slipped out of the pulling fingers short of its angle, shut again from there)
    start_look: Bool = False
    speed: Number = Field(None, gt=TURN_SPEED_RANGE_M_S[0], le=TURN_SPEED_RANGE_M_S[1],
                          description=f"m/s of the contact along the arc in ({TURN_SPEED_RANGE_M_S[0]:g}, "
                                      f"{TURN_SPEED_RANGE_M_S[1]:g}]")
    # false: the hand stays where it rose off the link (a tall door pulled open stands between it and home)
    return_home: Bool = True
    # true: the hand comes to the link from above its top (a door pulled open past square, shut again from its
    # outer side: the hand rises over it rather than through it)
    approach_over: Bool = False
    # true: after letting go the hand moves out along the link past its free end, and goes on from there round
    # that end rather than rising over the link (the arm behind a hand outside a tall door lies across its top);
    # home on the link's other side, it turns round the end to that side before it goes home
    withdraw_past_end: Bool = False

    @field_validator("turn", mode="before")
    @classmethod
    def _a_hinge(cls, link: str, info: ValidationInfo) -> str:
        hinges = _hinges(info)
        return _one_of(link, hinges, f"a hinge-jointed link from {sorted(hinges)}")

    @field_validator("to", "palm_from", mode="before")
    @classmethod
    def _within_the_range(cls, angle, info: ValidationInfo):
        link = info.data.get("turn")
        if link is None:                 # refused above already
            return angle
        lo, hi = _hinges(info)[link]
        if not is_number(angle) or not lo <= angle <= hi:
            raise ValueError(f"an angle in rad within the joint range [{lo:g}, {hi:g}]")
        return angle


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
        return _object(name, info, but=(info.data.get("strike"),))

    @field_validator("strike_point")
    @classmethod
    def _on_the_tool(cls, point: list[float], info: ValidationInfo) -> list[float]:
        tool = info.data.get("tool")
        if tool is None:
            return point
        lo, hi = parts_aabb(_scope(info).objects[tool].parts)
        if not all(a <= v <= b for v, a, b in zip(point, lo, hi)):
            raise ValueError(f"a point on the tool, within its bounding box from {[round(float(a), 3) for a in lo]} "
                             f"to {[round(float(b), 3) for b in hi]}")
        return point

    @field_validator("place", mode="before")
    @classmethod
    def _a_place(cls, place: str, info: ValidationInfo) -> str:
        return _object(place, info, but=(info.data.get("tool"),), extra=(TABLE_TARGET,))


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
    _slid_in_only = field_validator("slide_clearance_m", mode="before")(_slid_in)

    @field_validator("place", mode="before")
    @classmethod
    def _a_place(cls, place: str, info: ValidationInfo) -> str:
        if info.data.get("place_from") == PLACE_FROM_FRONT:
            return _front_container(place, info, but=(info.data.get("carry"),))
        return _object(place, info, but=(info.data.get("carry"),))

    @field_validator("grasp_height", mode="before")
    @classmethod
    def _within_its_height(cls, height: float, info: ValidationInfo) -> float:
        carried = info.data.get("carry")
        if carried is None:
            return height
        half_z = float(_scope(info).objects[carried].half_extents[2])
        if not is_number(height) or abs(height) > half_z:
            raise ValueError(f"metres from the object's centre in [{-half_z:g}, {half_z:g}]")
        return height


class HandoverStep(PlanStep, GraspFields):
    """{hand, handover, to_hand, at, [pick_from], [take_point], [take_roll_deg], [grasp], [grasp_point],
    [grasp_roll_deg], [approach_pitch_deg], [grasp_yaw], [after], [wait_s]}: `hand` gives the object to `to_hand` in the air,
    its centre at `at` [x, y, z] (table top; z above it). A hand that does not hold it yet picks it first,
    as `pick` with the grasp fields (pick_from: front, with grasp: side, takes it out level through the side
    a container is open at, a bottle out of a fridge). `to_hand` takes it from the other side with a side
    grasp at take_point (object frame, default its centre: clear of the giver's grasp_point), turned
    take_roll_deg about the fingers (as a side grasp's grasp_roll_deg, default 90: thumb up);
    the giver lets go and goes home. The next step of `to_hand` that names the object (a pour, a pick, a
    handover back) starts holding it."""

    grasps: ClassVar[tuple[str, ...]] = (SIDE_GRASP, "power")

    handover: TaskObject
    to_hand: Name
    at: AirPoint
    pick_from: PlaceFrom = "above"
    take_point: ObjectPoint = None
    take_roll_deg: RollDeg = None
    grasp_roll_deg: RollDeg = None

    @field_validator("to_hand", mode="before")
    @classmethod
    def _the_other_hand(cls, to_hand: str, info: ValidationInfo) -> str:
        others = [h for h in HANDS if h != info.data.get("hand")]
        return _one_of(to_hand, others, " or ".join(map(repr, others)) + " (the other hand)")

    @field_validator("pick_from", mode="before")
    @classmethod
    def _front_with_a_side_grasp(cls, way: str, info: ValidationInfo) -> str:
        if way == PLACE_FROM_FRONT and info.data.get("grasp") != SIDE_GRASP:
            raise ValueError(f"pick_from: {PLACE_FROM_FRONT} only with grasp: {SIDE_GRASP} (the hand comes in level)")
        return way

    _side_only = field_validator("grasp_roll_deg", mode="before")(_side_grasp_roll)


# a step's kind is the one of these fields it has
STEP_MODELS: dict[str, type[PlanStep]] = {
    "pick": PickStep, "drag": DragStep, "pour": PourStep, "press": PressStep, "turn": TurnStep,
    "carry": CarryStep, "strike": StrikeStep, "handover": HandoverStep,
}
