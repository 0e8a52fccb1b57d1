"""The plan's vocabulary and field types: words a step may use, ranges, and the checks that
validate a name against the task (`PlanScope` as validation context)."""

from __future__ import annotations

from typing import Annotated

from pydantic import BeforeValidator, Field, ValidationInfo

from ..base import Name, Number, is_number


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
PARK_OUT_RANGE_M = (0.0, 0.2)    # park_out_m: a hand parked this far outward of its home
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
LIFT_RANGE_M = (0.02, 0.3)      # lift_m: a pick lifted this far over its grasp and carried this far over its place
FOLD_RANGE = (0.0, 1.0)         # pinch_fold: a flat pinch's other fingers folded from open (0) to their closed end (1)
CARRY_RANGE_S = (0.0, 10.0)     # carry_s: a pick's carry, above 0 and at most 10 s
OPEN_RANGE_S = (0.0, 3.0)       # open_s: a pick's hand opening over its place before it rises, above 0 and at most 3 s
TOE_IN_RANGE_DEG = (0.0, 30.0)  # toe_in_deg: a carry's fingers turned in towards the object, level .. 30 degrees
SLIDE_CLEARANCE_RANGE_M = (0.0, 0.15)   # slide_clearance_m: a front place's object bottom over the cavity floor
GRASP_CLOSURE_RANGE = (1.0, 1.5)     # grasp_closure: a handover giver's tabletop grasp closed up to 1.5 times as far


# place_from: front: the object's bottom this far above the cavity floor as it slides in (default 4 cm)
SlideClearance = Annotated[Number, Field(ge=SLIDE_CLEARANCE_RANGE_M[0], le=SLIDE_CLEARANCE_RANGE_M[1],
                                         description=f"metres in [{SLIDE_CLEARANCE_RANGE_M[0]:g}, "
                                                     f"{SLIDE_CLEARANCE_RANGE_M[1]:g}]")]


def slid_in(value, info: ValidationInfo):
    """slide_clearance_m, slide_fingers_in, slide_as_held only with place_from: front (nothing slides in otherwise)."""
    if info.data.get("place_from") != PLACE_FROM_FRONT:
        raise ValueError(f"no {info.field_name} without place_from: {PLACE_FROM_FRONT} (nothing slides in)")
    return value


def vector_of(lengths: tuple[int, ...], words: str):
    """A list of finite numbers of one of these lengths; anything else is refused in ``words`` as a whole."""
    def check(value):
        if not isinstance(value, list) or len(value) not in lengths or not all(map(is_number, value)):
            raise ValueError(words)
        return value
    return Annotated[list[Number], BeforeValidator(check)]


PlaceOffset = vector_of((2, 3), "[dx, dy] or [dx, dy, dz] in metres")
TableSpot = vector_of((2,), "[x, y] of the table top in metres")
TableDirection = vector_of((2,), "[dx, dy], a direction on the table top")
ZoneOffset = vector_of((2,), "[dx, dy] from the zone's centre in metres")
ObjectPoint = vector_of((3,), "[x, y, z] in the object's frame, metres")
ObjectAxis = vector_of((3,), "[x, y, z], a direction in the object's frame")
AirPoint = vector_of((3,), "[x, y, z] of the table top in metres, z above it")


def only_with_grasp(grasp: str | tuple[str, ...], what: str):
    """A `before` check of a field that means something with one grasp (or one of several) only (``what`` it
    is): refused with any other grasp (the step's `grasp` is validated before it)."""
    grasps = (grasp,) if isinstance(grasp, str) else grasp

    def check(value, info: ValidationInfo):
        if info.data.get("grasp") not in grasps:
            raise ValueError(f"no {info.field_name} without grasp: {' or '.join(grasps)} ({what})")
        return value
    return check


side_grasp_roll = only_with_grasp(SIDE_GRASP, "the hand's turn about its fingers")
# a side grasp's turn about the fingers (grasp_roll_deg, take_roll_deg)
RollDeg = Annotated[Number, Field(ge=SIDE_ROLL_RANGE_DEG[0], le=SIDE_ROLL_RANGE_DEG[1],
                                  description=f"degrees in [{SIDE_ROLL_RANGE_DEG[0]:g}, {SIDE_ROLL_RANGE_DEG[1]:g}]")]


def plan_scope(info: ValidationInfo):
    return info.context["scope"]


def container_names(scope) -> list[str]:
    return sorted(n for n, o in scope.objects.items() if o.interior_half_extents is not None)


def one_of(value, names, expected: str) -> str:
    """`value` if it is one of `names` (checked before the field's type: anything else gets `expected`)."""
    if not isinstance(value, str) or value not in list(names):
        raise ValueError(expected)
    return value


def an_object(value: str, info: ValidationInfo, *, but: tuple = (), extra: tuple = ()) -> str:
    """An object of the task's (not one of ``but``), or one of the ``extra`` words."""
    names = sorted(n for n in plan_scope(info).objects if n not in but)
    also = "".join(f" or {e!r}" for e in extra)
    return one_of(value, [*names, *extra], f"an object from {names}{also}")


# a field naming one of the task's objects
TaskObject = Annotated[Name, BeforeValidator(lambda name, info: an_object(name, info))]
# place_from: lowered from above, or slid in level through the side a container is open at
PlaceFrom = Annotated[Name, BeforeValidator(lambda way: one_of(way, PLACE_FROM, f"one of {list(PLACE_FROM)}"))]


def front_container(place: str, info: ValidationInfo, *, but: tuple = ()) -> str:
    """`place` with place_from: front: one of the task's containers (not one of ``but``)."""
    containers = [c for c in container_names(plan_scope(info)) if c not in but]
    return one_of(place, containers, f"with place_from: front, a container from {containers}")


def hinge_ranges(info: ValidationInfo) -> dict:
    return {f"{n}/{link.name}": link.joint.range for n, o in plan_scope(info).objects.items() for link in o.links
            if link.joint.type == "hinge"}
