"""A task's `demo_plan`: what the scripted operator (teleop/scripted_operator.py) does, step by step.

Each step is one kind from STEP_KINDS, named by the field that says what it acts on: `pick` (carry
an object to a target), `drag` (pull a container into a zone), `pour` (tip a bottle's mouth over a
target), `press` (press keys or buttons in order), `turn` (swing a lid or a door to a joint angle),
`carry` (both hands carry an object between their palms), `strike` (hit a target once with a
tool, then put the tool away).
Every field is checked when the task loads, so a bad plan fails then, naming the step and the field.
A new kind is a new entry here with its check, and a planner in teleop/plan_steps/.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

from sim.errors import SpecError
from sim.scene.parts import parts_aabb

TABLE_TARGET = "table"      # place: table puts an object down at place_offset [x, y] of the table top (centre 0, 0)
PLAN_GRASPS = ("power", "pinch")
# `pick` also takes flat_pinch: the fingertips to the table beside a thin object lying flat
PICK_GRASPS = (*PLAN_GRASPS, "flat_pinch")
PINCHES = ("pinch", "flat_pinch")      # grasps that find their own hold: no grasp_point (but a pick's pinch may take one)
APPROACH_PITCH_RANGE_DEG = (0.0, 80.0)
GRASP_YAW_ACROSS = "across"   # grasp_yaw: the hand turned to close across the object's narrow side
HANDS = ("left", "right")
PLACE_FROM_FRONT = "front"
PLACE_FROM = ("above", PLACE_FROM_FRONT)   # pick's place_from: lowered from above, or slid in through a side opening
BOTH_HANDS = "both"          # `hand: both`: a step of both hands at once (kinds in BOTH_HANDS_KINDS)
# every kind's: wait_s, seconds the step waits after the steps in `after` end (or the episode starts),
# e.g. one hand closes a lid while the other is still putting the bottle it poured from away
COMMON_FIELDS = ("wait_s",)
WAIT_RANGE_S = (0.0, 60.0)


@dataclass(frozen=True)
class PlanScope:
    """What a plan step may name: the task's objects (name -> ObjectSpec), zones and points."""
    objects: dict
    zones: dict
    points: dict


@dataclass(frozen=True)
class StepKind:
    required: tuple[str, ...]
    optional: tuple[str, ...]
    check: Callable               # (path, where, step, scope: PlanScope) -> None; raises SpecError

    @property
    def fields(self) -> tuple[str, ...]:
        return self.required + self.optional + COMMON_FIELDS


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _check_object(path, where: str, step: dict, key: str, objects: dict, extra: tuple[str, ...] = ()) -> None:
    if not isinstance(step[key], str) or (step[key] not in objects and step[key] not in extra):
        also = "".join(f" or {e!r}" for e in extra)
        raise SpecError(path, f"{where}.{key}", f"an object from {sorted(objects)}{also}", step[key])


def _check_vector(path, where: str, step: dict, key: str, lengths: tuple[int, ...], expected: str) -> None:
    """An optional field of numbers, ``lengths`` long (absent: fine)."""
    if key not in step:
        return
    value = step[key]
    if not isinstance(value, (list, tuple)) or len(value) not in lengths or not all(map(_is_number, value)):
        raise SpecError(path, f"{where}.{key}", expected, value)


def _check_approach_pitch(path, where: str, step: dict) -> None:
    lo, hi = APPROACH_PITCH_RANGE_DEG
    pitch = step.get("approach_pitch_deg", 0.0)
    if not _is_number(pitch) or not lo <= pitch <= hi:
        raise SpecError(path, f"{where}.approach_pitch_deg", f"degrees in [{lo:g}, {hi:g}]", pitch)


def _check_grasp(path, where: str, step: dict, grasps: tuple[str, ...] = PLAN_GRASPS, default: str = "power",
                 across: bool = True, part_pinch: bool = False) -> None:
    """How a step that picks something up holds it: [grasp] (one of ``grasps``), [approach_pitch_deg],
    [grasp_yaw] (degrees, or with ``across`` also "across"), [grasp_point] (not with a pinch; with
    ``part_pinch``, a pinch closes on the part there, not flat_pinch)."""
    grasp = step.get("grasp", default)
    if grasp not in grasps:
        raise SpecError(path, f"{where}.grasp", f"one of {list(grasps)}", grasp)
    _check_approach_pitch(path, where, step)
    yaw = step.get("grasp_yaw", 0.0)
    if not (across and yaw == GRASP_YAW_ACROSS) and not (_is_number(yaw) and -180.0 <= yaw <= 180.0):
        expected = f"{GRASP_YAW_ACROSS!r} or degrees in [-180, 180]" if across else "degrees in [-180, 180]"
        raise SpecError(path, f"{where}.grasp_yaw", expected, yaw)
    _check_vector(path, where, step, "grasp_point", (3,), "[x, y, z] in the object's frame, metres")
    if "grasp_point" in step and grasp in (("flat_pinch",) if part_pinch else PINCHES):
        raise SpecError(path, f"{where}.grasp_point", f"no grasp_point with grasp: {grasp} (the pinch finds its own)",
                        step["grasp_point"])
    if "approach_pitch_deg" in step and grasp == "flat_pinch":
        raise SpecError(path, f"{where}.approach_pitch_deg", "no approach_pitch_deg with grasp: flat_pinch (the "
                        "hand turns its fingertips down to the table itself)", step["approach_pitch_deg"])


def _check_pick(path, where: str, step: dict, scope: PlanScope) -> None:
    """{hand, pick, place, [place_offset], [place_from], [grasp], [approach_pitch_deg], [grasp_yaw],
    [grasp_point], [after]}: place is an object, or `table` with place_offset the spot on the table top
    to set the object down at; place_from: front slides the object in level through the side a
    container is open at (a microwave, a fridge shelf; place_offset's dz then from the cavity floor),
    rather than lowering it from above; grasp_yaw turns the hand about the vertical (degrees, or
    "across" the object's narrow side); grasp_point is where a power grasp closes, or the part a pinch
    closes on (a bowl's rim), in the object's frame; grasp: flat_pinch picks a thin object lying flat
    with the fingertips (no grasp_point, no approach_pitch_deg)."""
    _check_object(path, where, step, "pick", scope.objects)
    _check_object(path, where, step, "place", scope.objects, extra=(TABLE_TARGET,))
    place_from = step.get("place_from", PLACE_FROM[0])
    if place_from not in PLACE_FROM:
        raise SpecError(path, f"{where}.place_from", f"one of {list(PLACE_FROM)}", place_from)
    if place_from == PLACE_FROM_FRONT:
        containers = sorted(n for n, o in scope.objects.items() if o.interior_half_extents is not None)
        if step["place"] not in containers:
            raise SpecError(path, f"{where}.place", f"with place_from: front, a container from {containers}",
                            step["place"])
    _check_vector(path, where, step, "place_offset", (2, 3), "[dx, dy] or [dx, dy, dz] in metres")
    _check_grasp(path, where, step, PICK_GRASPS, part_pinch=True)


DRAG_HOOK_DEPTH_M = 0.02   # drag: curled fingertips this far below the container's rim
DRAG_PITCH_DEG = 20.0      # ... the fingers tilted this far down into it


def _check_drag(path, where: str, step: dict, scope: PlanScope) -> None:
    """{hand, drag, to_zone, [place_offset], [hook_depth], [pitch_deg], [hook_closure], [after]}: pull a
    container across the table until its centre is at place_offset [dx, dy] from the zone's centre, the
    curled fingertips hook_depth below its rim, the fingers pitch_deg down and curled hook_closure of the
    wall hook (a tall box tips when full curl lifts its wall: pull low, barely curled)."""
    _check_object(path, where, step, "drag", scope.objects)
    if not isinstance(step["to_zone"], str) or step["to_zone"] not in scope.zones:
        raise SpecError(path, f"{where}.to_zone", f"a zone from {sorted(scope.zones)}", step["to_zone"])
    if scope.objects[step["drag"]].interior_half_extents is None:
        containers = sorted(n for n, o in scope.objects.items() if o.interior_half_extents is not None)
        raise SpecError(path, f"{where}.drag", f"a container from {containers}", step["drag"])
    _check_vector(path, where, step, "place_offset", (2,), "[dx, dy] from the zone's centre in metres")
    depth = step.get("hook_depth", DRAG_HOOK_DEPTH_M)
    height = 2 * scope.objects[step["drag"]].interior_half_extents[2]
    if not _is_number(depth) or not 0.0 < depth < height:
        raise SpecError(path, f"{where}.hook_depth", f"metres below the rim in (0, {height:.3f})", depth)
    pitch = step.get("pitch_deg", DRAG_PITCH_DEG)
    if not _is_number(pitch) or not 0.0 <= pitch <= 80.0:
        raise SpecError(path, f"{where}.pitch_deg", "degrees in [0, 80]", pitch)
    closure = step.get("hook_closure", 1.0)
    if not _is_number(closure) or not 0.0 < closure <= 1.0:
        raise SpecError(path, f"{where}.hook_closure", "a fraction of the wall hook's curl in (0, 1]", closure)


def _check_press(path, where: str, step: dict, scope: PlanScope) -> None:
    """{hand, press: [<object>/<link>, ...], [after]}: press these slide-jointed links (keys, buttons) in order."""
    keys = sorted(f"{n}/{link.name}" for n, o in scope.objects.items() for link in o.links
                  if link.joint.type == "slide")
    press = step["press"]
    if not isinstance(press, list) or not press or not all(isinstance(k, str) and k in keys for k in press):
        raise SpecError(path, f"{where}.press", f"a non-empty list of slide-jointed links from {keys}", press)


POUR_TILT_RANGE_DEG = (50.0, 150.0)  # mouth axis from vertical: a pour threshold .. near upside down
POUR_DEFAULT_TILT_DEG = 85.0         # a person's pour: the bottle near horizontal, well past 50
POUR_GRASPS = ("side", *PLAN_GRASPS)  # side: palm against a tall bottle, thumb up (a person's hold)
POUR_DEFAULT_GRASP = "side"


def _check_pour(path, where: str, step: dict, scope: PlanScope) -> None:
    """{hand, pour, into, [tilt_deg], [grasp], [approach_pitch_deg], [grasp_yaw], [grasp_point], [place_offset],
    [after]}: tip a pourer (an object with a `mouth_axis`) over `into` (an object, or a task point:
    poured just above it), then set it down where it was or at place_offset [x, y] of the table top;
    grasp_yaw (degrees) turns the hand about the vertical before it closes and grasp_point is where it
    closes, in the pourer's frame (as for `pick`: e.g. a side grasp held above the middle and off the
    palm, so that the thumb comes down beside a bottle's shoulder, not onto it)."""
    pourers = sorted(n for n, o in scope.objects.items() if o.mouth_axis is not None)
    if step["pour"] not in pourers:
        raise SpecError(path, f"{where}.pour", f"an object with a mouth_axis from {pourers}", step["pour"])
    others = sorted(n for n in scope.objects if n != step["pour"])
    if not isinstance(step["into"], str) or (step["into"] not in others and step["into"] not in scope.points):
        raise SpecError(path, f"{where}.into", f"an object from {others} or a point from {sorted(scope.points)}",
                        step["into"])
    lo, hi = POUR_TILT_RANGE_DEG
    tilt = step.get("tilt_deg", POUR_DEFAULT_TILT_DEG)
    if not _is_number(tilt) or not lo <= tilt <= hi:
        raise SpecError(path, f"{where}.tilt_deg", f"degrees in [{lo:g}, {hi:g}]", tilt)
    _check_vector(path, where, step, "place_offset", (2,), "[x, y] of the table top in metres")
    # grasp_yaw in degrees only: "across" is worked out for a hand closing from above
    _check_grasp(path, where, step, POUR_GRASPS, POUR_DEFAULT_GRASP, across=False)


def _check_turn(path, where: str, step: dict, scope: PlanScope) -> None:
    """{hand, turn: <object>/<link>, to: <angle, rad>, [palm_from], [after]}: swing a hinge-jointed link
    (a lid, a door) to an angle within its joint range; from the link angle palm_from on (rad, within
    the range) the flat palm pushes, fingers along the hinge, instead of the fingertips."""
    hinges = {f"{n}/{link.name}": link.joint.range for n, o in scope.objects.items() for link in o.links
              if link.joint.type == "hinge"}
    if not isinstance(step["turn"], str) or step["turn"] not in hinges:
        raise SpecError(path, f"{where}.turn", f"a hinge-jointed link from {sorted(hinges)}", step["turn"])
    lo, hi = hinges[step["turn"]]
    if not _is_number(step["to"]) or not lo <= step["to"] <= hi:
        raise SpecError(path, f"{where}.to", f"an angle in rad within the joint range [{lo:g}, {hi:g}]", step["to"])
    if "palm_from" in step and not (_is_number(step["palm_from"]) and lo <= step["palm_from"] <= hi):
        raise SpecError(path, f"{where}.palm_from", f"an angle in rad within the joint range [{lo:g}, {hi:g}]",
                        step["palm_from"])


def _check_strike(path, where: str, step: dict, scope: PlanScope) -> None:
    """{hand, strike, tool, strike_point, place, [place_offset], [grasp], [grasp_point], [grasp_yaw],
    [approach_pitch_deg], [after]}: pick the tool up (grasp fields as for `pick`), strike the target
    object once with the tool's strike_point (tool frame, on the tool), then put the tool onto or
    into `place` (an object, or `table` with place_offset a spot of the table top)."""
    _check_object(path, where, step, "strike", scope.objects)
    others = {n: o for n, o in scope.objects.items() if n != step["strike"]}
    _check_object(path, where, step, "tool", others)
    _check_vector(path, where, step, "strike_point", (3,), "[x, y, z] in the tool's frame, metres")
    lo, hi = parts_aabb(scope.objects[step["tool"]].parts)
    if not all(a <= v <= b for v, a, b in zip(step["strike_point"], lo, hi)):
        raise SpecError(path, f"{where}.strike_point", f"a point on the tool, within its bounding box from "
                        f"{[round(float(a), 3) for a in lo]} to {[round(float(b), 3) for b in hi]}",
                        step["strike_point"])
    places = {n: o for n, o in scope.objects.items() if n != step["tool"]}
    _check_object(path, where, step, "place", places, extra=(TABLE_TARGET,))
    _check_vector(path, where, step, "place_offset", (2, 3), "[dx, dy] or [dx, dy, dz] in metres")
    _check_grasp(path, where, step)


BOTH_HANDS_KINDS = ("carry",)   # kinds whose step takes `hand: both`


def _check_carry(path, where: str, step: dict, scope: PlanScope) -> None:
    """{hand: both, carry, place, [place_offset], [grasp_height], [return_home], [after]}: both palms
    squeeze the object from opposite sides and carry it onto/into `place` (place_offset as for pick);
    grasp_height (metres from its centre, within its half height) is where the palms press;
    return_home: true sends both hands back to their home pose after letting go."""
    if step["hand"] != BOTH_HANDS:
        raise SpecError(path, f"{where}.hand", f"{BOTH_HANDS!r} (a carry takes both hands)", step["hand"])
    _check_object(path, where, step, "carry", scope.objects)
    others = {n: o for n, o in scope.objects.items() if n != step["carry"]}
    _check_object(path, where, step, "place", others)
    _check_vector(path, where, step, "place_offset", (2, 3), "[dx, dy] or [dx, dy, dz] in metres")
    half_z = float(scope.objects[step["carry"]].half_extents[2])
    height = step.get("grasp_height", 0.0)
    if not _is_number(height) or abs(height) > half_z:
        raise SpecError(path, f"{where}.grasp_height", f"metres from the object's centre in [{-half_z:g}, {half_z:g}]",
                        height)
    if not isinstance(step.get("return_home", False), bool):    # after letting go, both hands go back home
        raise SpecError(path, f"{where}.return_home", "true or false", step["return_home"])


STEP_KINDS: dict[str, StepKind] = {
    "pick": StepKind(("hand", "pick", "place"),
                     ("place_offset", "grasp", "approach_pitch_deg", "grasp_yaw", "grasp_point", "after", "place_from"),
                     _check_pick),
    "drag": StepKind(("hand", "drag", "to_zone"), ("place_offset", "hook_depth", "pitch_deg", "hook_closure", "after"),
                     _check_drag),
    "pour": StepKind(("hand", "pour", "into"),
                     ("tilt_deg", "grasp", "approach_pitch_deg", "grasp_yaw", "grasp_point", "place_offset", "after"),
                     _check_pour),
    "press": StepKind(("hand", "press"), ("after",), _check_press),
    "turn": StepKind(("hand", "turn", "to"), ("palm_from", "after"), _check_turn),
    "carry": StepKind(("hand", "carry", "place"), ("place_offset", "grasp_height", "after", "return_home"),
                      _check_carry),
    "strike": StepKind(("hand", "strike", "tool", "strike_point", "place"),
                       ("place_offset", "grasp", "grasp_point", "grasp_yaw", "approach_pitch_deg", "after"), _check_strike),
}
PLAN_STEP = " or ".join("{" + ", ".join(k.required) + ", ...}" for k in STEP_KINDS.values())


def step_kind(step: dict) -> str:
    """The kind of a (checked) plan step: the one STEP_KINDS key among its fields."""
    return next(kind for kind in STEP_KINDS if kind in step)


def parse_plan(path, raw: dict, scope: PlanScope) -> list[dict]:
    """The task's `demo_plan`, every step checked. `after` lists earlier steps (by index) that must
    end before this one starts (the two hands otherwise work at once); `wait_s` holds it that many
    seconds longer."""
    plan = raw.get("demo_plan") or []
    if not isinstance(plan, list):
        raise SpecError(path, "demo_plan", f"a list of steps {PLAN_STEP}", plan)
    for i, step in enumerate(plan):
        where = f"demo_plan[{i}]"
        kinds = [k for k in STEP_KINDS if isinstance(step, dict) and k in step]
        if len(kinds) != 1:
            raise SpecError(path, where, f"a mapping with exactly one of {', '.join(map(repr, STEP_KINDS))}: "
                                         f"{PLAN_STEP}", step)
        kind = STEP_KINDS[kinds[0]]
        for key in step:
            if key not in kind.fields:
                raise SpecError(path, f"{where}.{key}", f"one of the step's fields {list(kind.fields)}", step[key])
        for key in kind.required:
            if key not in step:
                raise SpecError(path, f"{where}.{key}", "a value")
        hands = (*HANDS, BOTH_HANDS) if kinds[0] in BOTH_HANDS_KINDS else HANDS
        if step["hand"] not in hands:
            raise SpecError(path, f"{where}.hand", " or ".join(map(repr, hands)), step["hand"])
        after = step.get("after", [])
        if not isinstance(after, list) or not all(isinstance(j, int) and not isinstance(j, bool) and 0 <= j < i
                                                  for j in after):
            raise SpecError(path, f"{where}.after", f"a list of earlier step indices (0..{i - 1})", after)
        lo, hi = WAIT_RANGE_S
        if "wait_s" in step and not (_is_number(step["wait_s"]) and lo <= step["wait_s"] <= hi):
            raise SpecError(path, f"{where}.wait_s", f"seconds in [{lo:g}, {hi:g}]", step["wait_s"])
        kind.check(path, where, step, scope)
    return plan
