"""Plan step `pick`'s parts (teleop/plan_steps/pick.py puts them together): carry an object to a target
(another object, or a spot of the table).

Approach, descend, close, lift, carry, lower, open, retreat; palm down, or with the fingers pitched
down (`approach_pitch_deg`), turned about the vertical (`grasp_yaw`). Where the object sits in the
hand and how the hand closes come from the hand file's palm grasp (at the object's `grasp_point`), or,
with `grasp: pinch`, from a pinch found from the hand's kinematics (teleop/pinch_grasp.py), or with
`grasp: flat_pinch`, from the fingertips' pinch for thin objects lying flat (teleop/flat_pinch.py),
or with `grasp: side`, the palm grasp turned thumb up around an upright part (a drill's grip).
Where the object goes comes from `place_offset`.
"""

from __future__ import annotations

import functools

import mujoco
import numpy as np

from sim.demo_plan import GRASP_YAW_ACROSS, SIDE_GRASP, TABLE_TARGET
from sim.embodiment.mirror import mirror_vec
from sim.physics import CONTROL_HZ
from sim.scene.reach import PALM_DOWN
from teleop.flat_pinch import (flat_pinch_rotation, near_rotations, refolded, tip_axis, tip_pinch, tip_preshape,
                                tips_over_lowest, width_along)
from teleop.operator_motion import (APPROACH_HEIGHT_M, DURATIONS, FORWARD, LIFT_HEIGHT_M, UP, SideTimeline,
                                    axis_rotation, pitched_palm_down, quat, yaw_of, yawed)
from teleop.pinch_grasp import pinch_axis_in_site_frame, pinch_fingers, pinch_grasp, pinch_preshape, thumb_actuators
from teleop.pinch_squeeze import squeezed
from teleop.pinch_tips import tips_clear_preshape
from teleop.plan_steps.flat_place import flat_place
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.own_arm import OWN_ARM_DEPTH_M, arm_into_scene
from teleop.plan_steps.part_pinch import part_width
from teleop.transit import bounding_box_points, hand_outline


# Power grasp closure per actuator group (early, late), each 0 = open .. 1 = grasp target. Closing:
# the early actuators (fingers) form a wall, then the late ones (thumb) press the object against it.
# Releasing opens both together: a thumb kept in opposition hooks the fruit as the hand lifts and
# flicks it off the plate.
WALL, CLOSED = (1.0, 0.0), (1.0, 1.0)
PINCH_SPREAD_MARGIN_M = 0.025  # pinch pre-shape: pads this much wider apart than the object
RELEASE_GAP_M = 0.005         # lowered to just above the plate: fruit let go higher bounces and rolls
PALM_CLEARANCE_M = 0.004
SIDE_GRASP_ROLL_DEG = 90.0    # `grasp: side`: the right hand turned palm towards the body's midline, thumb up
SIDE_GRASP_IN_M = 0.05        # `grasp: side` comes down this far out from the object, then moves in level
PALM_NORMAL = PALM_DOWN.T @ -UP   # out of the palm, wrist-site frame
CARRY_CLEARANCE_M = 0.02      # the carried object's bottom above its target's top, moving across


def place_offset(item: dict) -> np.ndarray:
    """A plan step's `place_offset` (checked when the task loads): [dx, dy] from the target's centre,
    optionally dz from its top (negative: lowered into a container and let go just above its floor
    rather than its rim); for `place: table`, the [x, y] of the table top to set the object down at."""
    return np.array([*item.get("place_offset", [0.0, 0.0]), 0.0][:3], float)


def approach_pitch(item: dict) -> float:
    """A plan step's `approach_pitch_deg`: how far the fingers point down from horizontal (0 = palm
    down, fingers forward). A person tilts the hand for small or low objects so the forearm stays
    clear of the table; a robot arm's wrist links need the same."""
    return float(item.get("approach_pitch_deg", 0.0))


@functools.lru_cache(maxsize=None)
def level_pinch_pitch(hand_name: str, fingers: tuple[str, ...] | None = None) -> float:
    """The finger pitch (degrees, 0..60) that levels the hand's pinch axis, so that the thumb and
    the fingers come down to the same height beside a low object instead of the lower one landing
    on it; 0 where the axis already falls towards the fingers (pitching would only tilt it more)."""
    axis = pinch_axis_in_site_frame(hand_name, fingers)
    pitches = np.arange(0.0, 61.0)
    elevation = np.array([(pitched_palm_down(p) @ axis)[2] for p in pitches])
    return float(pitches[np.argmin(np.abs(elevation))]) if elevation[0] > 0 else 0.0


def grasp_kind(item: dict) -> str:
    """A plan step's `grasp`: "power" (the hand's palm grasp, default), "pinch" (thumb against the
    first fingers' pads, for objects too small for the palm; teleop/pinch_grasp.py) or "flat_pinch"
    (the fingertips' pinch for a thin object lying flat: they come down to the table beside it;
    teleop/flat_pinch.py) or "side" (the palm grasp turned thumb up: side_roll). With flat_pinch,
    `grasp_yaw` in degrees is the direction the tips close along (world, from +x; from the object's x axis
    with `grasp_yaw_object: true`); "across" or none:
    across the object's narrowest horizontal width."""
    return item.get("grasp", "power")


# flat pinch: the hand's lowest point this far into the table top (the finger servos give; the tips stay
# on it): 2 mm above it, 3 of 6 jigsaw pieces were lifted (stream path), 8 mm into it, 6 of 6
FLAT_PINCH_PRESS_M = 0.008
FLAT_PINCH_STAGES = 4     # flat pinch: closing in this many stages, the wrist following the lowest point down


# grasp_arm_clear: another turn of the hand only with every arm joint within this of the planned grasp's (the
# RH5DG2's clear turns: 0.2-0.45 rad away; a wrist flipped to the other branch: 3.3-4.1)
SAME_BRANCH_RAD = 1.0


def flat_pinch(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str):
    """`grasp: flat_pinch` (flat_pinch_turned); with `grasp_arm_clear: true`, where the arm at the closed grasp
    runs more than OWN_ARM_DEPTH_M into the scene (an object, the table), the first of the other near-best turns of
    the hand (flat_pinch.near_rotations) whose arm touches none of it, if any: taking the marker with the RH5DG2's
    pinch, the UR5's wrist_1 link 25 cm back from the hand pressed on the pen cup's rim (150-200 N) and held the tips
    over the marker; the hand rolled 15-20 degrees further about its fingers keeps it clear."""
    planned = flat_pinch_turned(op, data, item, name)
    if not item.get("grasp_arm_clear"):
        return planned
    side = op.sides[item["hand"]]
    here = op.planned_place(data, name, side["timeline"].end)[0] if item.get("from_plan") else op.object_pos(data, name)

    def reached(pinch) -> tuple[float, np.ndarray]:
        """How deep the arm goes into the scene at the pinch's closed grasp, and its joints there."""
        hand_rot, _, offset, closing = pinch
        pose = (np.array([*(here - offset)[:2], closing[-1][2]]), quat(hand_rot))
        return arm_into_scene(op, data, side, [pose], side["q"]), side["kin"].ik(*pose, side["q"]).q

    depth, q = reached(planned)
    if depth <= OWN_ARM_DEPTH_M:
        return planned
    choice = 1
    while True:
        try:
            other = flat_pinch_turned(op, data, item, name, choice)
        except IndexError:          # none of them keeps clear: as planned
            return planned
        depth, q_other = reached(other)
        # clear, not grazing (3-4 mm deep in the check, the UR5 pressed on the cup at 45-64 N), and the arm's joints
        # near the planned ones: another wrist branch (3.3-3.5 rad away, the UR5+Wuji's pen) the arm strays to reach
        if depth == 0.0 and np.max(np.abs(q_other - q)) <= SAME_BRANCH_RAD:
            return other
        choice += 1


def flat_pinch_turned(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str, choice: int = 0):
    """`grasp: flat_pinch` (teleop/flat_pinch.py): the hand turned so that the thumb's and the
    fingers' tips are its lowest points, yawed (`grasp_yaw`) and spread across the object, comes down
    until its lowest point presses onto the table beside the object, then closes in stages, the wrist
    following the lowest point as the fingers curl so the tips stay on the table, as a person picks
    up a key; the tips close either side of the object's centre, or of its `grasp_point`. Returns
    (hand rotation, pre-shape, object centre from the wrist, closing keyframes)."""
    side = op.sides[item["hand"]]
    hand, left = side["hand"], item["hand"] == "left"
    obj = op.scene.task.objects[name]
    body = op.scene.object_body_ids[name]
    lo, hi = op.scene.model.actuator_ctrlrange[side["hand_ids"]].T
    fingers = pinch_fingers(item)       # `pinch_fingers`: the pad pinch set the tips come from (default the hand's)
    close = np.clip(tip_pinch(hand, fingers).close, lo, hi)
    if item.get("pinch_fold") is not None:     # the other fingers folded that far instead (flat_pinch.refolded)
        close = np.clip(refolded(hand, close, float(item["pinch_fold"]), fingers), lo, hi)
    body_rot = data.xmat[body].reshape(3, 3)
    at = body_rot @ grasp_point(item)       # the tips close there: the centre, or a grasp_point (a handle)
    mirror = mirror_vec if left else (lambda v: v)

    def turned(q_turn: np.ndarray, q_axis: np.ndarray) -> np.ndarray:
        """Tips at the bottom for shape ``q_turn`` (``choice``: the near-best turn that many from the best); yawed by
        the tips' axis at ``q_axis``."""
        if choice:        # IndexError past the last
            R = near_rotations(hand, item["hand"], tuple(np.round(q_turn, 6)), fingers)[choice]
        else:
            R = flat_pinch_rotation(hand, item["hand"], q_turn, fingers)
        closing = R @ mirror(tip_axis(hand, q_axis, fingers))
        if item.get("grasp_yaw", GRASP_YAW_ACROSS) == GRASP_YAW_ACROSS:
            return yawed(R, across_turn(closing, body_rot, obj.half_extents))
        # degrees: the direction the tips close along (world, from +x; `grasp_yaw_object`: from the object's x axis
        # as it lies, so the tips meet its sides at the same angle however it was left turned), either way round
        start = yaw_of(body_rot) if item.get("grasp_yaw_object") else 0.0
        turn = np.radians(item["grasp_yaw"]) + start - np.arctan2(closing[1], closing[0])
        return yawed(R, float((turn + np.pi / 2) % np.pi - np.pi / 2))

    # the object's centre goes where the tips are as far apart as it is wide (through its centre,
    # along their axis): both sides touch it at once, rather than one pushing it across the table into
    # the other; the shape and the width depend on each other: a first guess from the open hand
    touch = side["open"]
    for q_turn in (close, None):
        hand_rot = turned(touch if q_turn is None else q_turn, touch)
        width = width_along(op.scene.model, data, body, hand_rot @ mirror(tip_axis(hand, touch, fingers)),
                            data.xpos[body] + at)
        touch, centre = tip_preshape(hand, side["open"], close, width, fingers)
    ready, _ = tip_preshape(hand, side["open"], close, width + PINCH_SPREAD_MARGIN_M, fingers)
    # the last stage presses the tips past each other with grasp_squeeze_m (the wrist as planned for `close`)
    last = np.clip(squeezed(hand, close, ready, item["grasp_squeeze_m"], fingers), lo, hi) if item.get("grasp_squeeze_m") else close
    press = FLAT_PINCH_PRESS_M
    if item.get("grasp_tips_height_m") is not None:
        # the last stage's tips end that high on the part (half a handle's height), never pressed deeper than by
        # default: pressed 8 mm, a linkage finger (one actuator, the tip the lowest point) stuck on the table and
        # did not close; squeezed tips curl 3-5 mm higher than `close`'s
        press = min(press, tips_over_lowest(hand, item["hand"], last, hand_rot, close, fingers) - float(item["grasp_tips_height_m"]))
    bottom = float(bounding_box_points(op.scene.model, data, body)[:, 2].min()) - press
    shapes = [ready + k / FLAT_PINCH_STAGES * (close - ready) for k in range(FLAT_PINCH_STAGES + 1)]
    below = [float(-(hand_outline(hand, item["hand"], q) @ hand_rot.T)[:, 2].min()) for q in shapes]
    obj_z = op.object_pos(data, name)[2]
    offset = np.array([*((hand_rot @ mirror(centre))[:2] - at[:2]), obj_z - (bottom + below[0])])
    per = (DURATIONS["close"] + DURATIONS["close_late"]) // FLAT_PINCH_STAGES
    closing = [(per, q, bottom + b) for q, b in zip(shapes[1:], below[1:])]
    if item.get("grasp_squeeze_m"):
        closing[-1] = (per, last, closing[-1][2])
    return hand_rot, ready, offset, closing


def power_closing(op: PlanningOperator, side: dict, item: dict) -> list:
    """A palm grasp's closing keyframes: the early actuators form a wall, then the late ones press the object
    against it. `close_thumb_last: true` makes the thumb's actuators (those moving its tip) the late ones,
    whatever the hand file declares: on the Wuji a thumb closing with the fingers reached a 5.4 cm lemon
    first and flicked it out on the lift (citrus_plate_loading). `grasp_closure` (a handover's) closes a
    hand's declared tabletop grasp, sized for fruit, that many times as far from open (within the actuators'
    ranges), so that a thinner part is squeezed, not only surrounded: the Shadow's and the Wuji's closed round
    a bottle's 3 cm neck without touching it. A hand's power grasp is left as it is (it curls round a bar).
    `thin_grasp: true` closes to the hand file's targets for a thin object where it declares them
    (`tabletop_grasp.thin_close`, fingers only): the Wuji's, eased to 0.7 of its power grasp for a 6.4 cm jar,
    did not reach a 4 cm pill bottle (medicine_shoebox_pack)."""
    if item.get("thin_grasp"):
        side = {**side, "closed": side["thin_closed"]}
    if item.get("close_thumb_last"):
        wall = np.where(thumb_actuators(side["hand"]), side["open"], side["closed"])
    else:
        wall = op.power(side, WALL)
    closed = op.power(side, CLOSED)
    scale = item.get("grasp_closure")
    if scale is not None and side["tabletop"]:    # a power grasp curls round a bar already
        lo, hi = op.scene.model.actuator_ctrlrange[side["hand_ids"]].T
        wall, closed = (np.clip(side["open"] + scale * (t - side["open"]), lo, hi) for t in (wall, closed))
    return [(DURATIONS["close"], wall, None), (DURATIONS["close_late"], closed, None)]


def side_roll(item: dict) -> float:
    """The turn (degrees, about the fingers) of a `grasp: side`: palm towards the body's midline,
    thumb up, as a person takes a drill by its grip or a bottle by its body; `grasp_roll_deg` past 90
    turns the palm partly up (the thumb leans out, clear of a part above the grip, and the held object
    settles onto the palm); 0 for the other grasps."""
    if item.get("grasp") != SIDE_GRASP:
        return 0.0
    roll = float(item.get("grasp_roll_deg", SIDE_GRASP_ROLL_DEG))
    return roll * (1.0 if item["hand"] == "right" else -1.0)


def grasp_point(item: dict) -> np.ndarray:
    """A plan step's `grasp_point` [x, y, z] (object frame, metres): where the hand closes, for an
    object held by a part (a pan by its handle); default its centre. Power grasps, and pinches (the pads
    close on the part there: teleop/plan_steps/part_pinch.py)."""
    return np.asarray(item.get("grasp_point", [0.0, 0.0, 0.0]), float)


def grasp_yaw(item: dict, hand_rot: np.ndarray, hand_name: str, body_rot: np.ndarray, half_extents,
              pinch: bool) -> float:
    """The turn (radians, about the vertical) a plan step's `grasp_yaw` asks of the hand: degrees, or
    "across": the hand closes across the object's narrowest horizontal width, as a person picks up a
    pen or a wrench (the pinch axis along that width; for a power grasp, the fingers curl along it,
    the object lying across the palm). Of the two turns that do it, the smaller."""
    value = item["grasp_yaw"]
    if value != GRASP_YAW_ACROSS:
        return float(np.radians(value))
    if pinch:
        axis = pinch_axis_in_site_frame(hand_name, pinch_fingers(item))
        closing = hand_rot @ (mirror_vec(axis) if item["hand"] == "left" else axis)
    else:
        closing = hand_rot @ (PALM_DOWN.T @ FORWARD)
    return across_turn(closing, body_rot, half_extents)


def across_turn(closing: np.ndarray, body_rot: np.ndarray, half_extents) -> float:
    """The smaller turn (radians, about the vertical) that sets the hand's ``closing`` direction
    (world) across the object's narrowest horizontal width."""
    angles = np.radians(np.arange(0.0, 180.0))
    directions = np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=1)
    widths = np.abs(directions @ body_rot) @ np.asarray(half_extents, float)
    narrow = angles[int(np.argmin(widths))]
    turn = narrow - np.arctan2(closing[1], closing[0])
    return float((turn + np.pi / 2) % np.pi - np.pi / 2)     # a closing direction has no sign


def turned_about_fingers(hand_rot: np.ndarray, roll_deg: float) -> np.ndarray:
    """The hand turned ``roll_deg`` about its fingers (a side grasp's roll: 90, thumb up)."""
    fingers = hand_rot @ (PALM_DOWN.T @ FORWARD)
    return axis_rotation(fingers, np.radians(roll_deg)) @ hand_rot


def side_grasp_offset(op: PlanningOperator, data: mujoco.MjData, side: dict, name: str, hand_rot: np.ndarray,
                      at: np.ndarray) -> np.ndarray:
    """The object centre's offset from the wrist site (world) for a palm grasp turned ``hand_rot`` that moved
    in level: the palm just short of the part at ``at`` (world, from the object's centre)."""
    clear = 0.5 * part_width(op.scene.model, data, op.scene.object_body_ids[name], op.object_pos(data, name) + at,
                             hand_rot[:, 1]) + PALM_CLEARANCE_M
    cx, cy, cz = side["grasp_centre"]
    return hand_rot @ np.array([cx, max(cy, clear), cz]) - at


def grasp_and_lift(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str,
                   roll_deg: float = 0.0, side_in_m: float = 0.0) -> np.ndarray:
    """Append the hand's approach to object ``name``, descent, closing and lift (the step's `grasp`
    and `approach_pitch_deg`; ``roll_deg`` turns the hand about the fingers first, e.g. 90: a tall
    bottle held from the side, thumb up); ``side_in_m``: the hand comes down that far out along its
    palm's normal, from above the object's top, and moves in level (a part above the grasped one, a
    drill's motor over its grip, stays clear of the open fingers) until the palm is just short of the
    part at the grasp point; return the object centre's offset from the wrist site (world) as held."""
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    obj = op.scene.task.objects[name]
    half_z = obj.half_extents[2]
    pinch = grasp_kind(item) == "pinch"
    if pinch and "approach_pitch_deg" not in item:
        hand_rot = pitched_palm_down(level_pinch_pitch(side["hand"], pinch_fingers(item)))
    else:
        hand_rot = pitched_palm_down(approach_pitch(item))
    if roll_deg:
        hand_rot = turned_about_fingers(hand_rot, roll_deg)
    body_rot = data.xmat[op.scene.object_body_ids[name]].reshape(3, 3)
    if "grasp_yaw" in item:
        hand_rot = yawed(hand_rot, grasp_yaw(item, hand_rot, side["hand"], body_rot, obj.half_extents, pinch))
    open_ = side["open"]
    if grasp_kind(item) == "flat_pinch":
        hand_rot, ready, offset, closing = flat_pinch(op, data, item, name)
    elif pinch:
        # come down with the pads spread wider than the object, its centre midway between them
        fingers = pinch_fingers(item)
        axis = pinch_axis_in_site_frame(side["hand"], fingers)
        axis = hand_rot @ (mirror_vec(axis) if item["hand"] == "left" else axis)
        width = 2.0 * float(np.abs(body_rot.T @ axis) @ obj.half_extents) + PINCH_SPREAD_MARGIN_M
        at = body_rot @ grasp_point(item)     # with a grasp_point: the pads close on the part there (part_pinch.py)
        if "grasp_point" in item:
            width = part_width(op.scene.model, data, op.scene.object_body_ids[name], op.object_pos(data, name) + at,
                               axis) + PINCH_SPREAD_MARGIN_M
        # the pads towards the thumb's (the step's own fingers, else the hand's), within the actuator ranges
        close = np.clip(pinch_grasp(side["hand"], fingers).close, *op.scene.model.actuator_ctrlrange[side["hand_ids"]].T)
        # with pinch_clear_tips: spread until the curled fingertips clear the part too
        preshape = tips_clear_preshape if item.get("pinch_clear_tips") else pinch_preshape
        ready, centre = preshape(side["hand"], open_, close, width, fingers)
        offset = hand_rot @ (mirror_vec(centre) if item["hand"] == "left" else centre) - at
        closing = [(DURATIONS["close"] + DURATIONS["close_late"], close, None)]
    else:
        at = body_rot @ grasp_point(item)
        if side_in_m:       # moved in level: the palm stops just short of the part at the grasp point
            offset = side_grasp_offset(op, data, side, name, hand_rot, at)
        else:
            # object centre in the wrist-site frame: the hand's grasp centre, lifted clear of the palm
            cx, cy, cz = side["grasp_centre"]
            if roll_deg:        # the object's depth along the palm normal, rather than its height
                half_z = float(np.abs(body_rot.T @ hand_rot[:, 1]) @ obj.half_extents)
            # the palm clears the object's top, measured from the grasped point rather than its centre
            # the hand closes on the grasp point; the object's centre sits `at` back from it
            clear = half_z - at[2] + PALM_CLEARANCE_M
            offset = hand_rot @ np.array([cx, max(cy, clear), cz]) - at
        closing = power_closing(op, side, item)
        ready = open_
    hand_quat = quat(hand_rot)
    # `from_plan: true`: where an earlier step of the plan leaves it (a drag); planned from where it lay, the
    # look below moved the grasp but not the carry's transit, which rose from there and swung the hand back
    here = op.planned_place(data, name, tl.end)[0] if item.get("from_plan") else op.object_pos(data, name)
    grasp = here - offset
    reach = len(tl.frames)
    beside = grasp - side_in_m * (hand_rot @ PALM_NORMAL)     # out from the object, along the palm's normal
    above = APPROACH_HEIGHT_M
    if side_in_m:       # the hand on its side reaches down as far as across: it comes from above the object's top
        top = float(bounding_box_points(op.scene.model, data, op.scene.object_body_ids[name])[:, 2].max())
        above += max(0.0, top - grasp[2])
    op.set_off(side, data, item, DURATIONS["approach"], pos=beside + above * UP, quat=hand_quat, hand=ready)
    tl.add(DURATIONS["descend"], pos=beside)
    if side_in_m:
        tl.add(DURATIONS["descend"], pos=grasp)
    for duration, targets, wrist_z in closing:
        if wrist_z is None:
            tl.add(duration, hand=targets)
        else:
            tl.add(duration, hand=targets, pos=np.array([*grasp[:2], wrist_z]))
    tl.add(DURATIONS["hold"])
    tl.add(DURATIONS["lift"], pos=grasp + lift_height(item) * UP)
    op.look_again(side, name, data, reach, len(tl.frames), planned=here)
    return offset


def planned_top(op: PlanningOperator, data: mujoco.MjData, name: str, step: int) -> tuple[np.ndarray, float]:
    """Where object ``name`` is at control step ``step`` as the plan leaves it (its centre), and its top's height."""
    pos = op.planned_place(data, name, step)[0]
    return pos, float(pos[2] + op.scene.task.objects[name].half_extents[2])


def place_centre(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str) -> np.ndarray:
    """Where object ``name``'s centre is let go: over the step's `place` target at `place_offset`,
    the release gap above where it comes to rest."""
    task = op.scene.task
    offset_xyz = place_offset(item)
    obj = task.objects[name]
    if item["place"] == TABLE_TARGET:       # set down at a spot of the table top
        place_xy = offset_xyz[:2]
        place_z = op.scene.table_height + offset_xyz[2] + obj.rest_height + RELEASE_GAP_M
    else:
        target = task.objects[item["place"]]
        place_xy = op.object_pos(data, item["place"])[:2] + offset_xyz[:2]
        place_z = (op.object_pos(data, item["place"])[2] + target.half_extents[2] + offset_xyz[2]
                   + obj.half_extents[2] + RELEASE_GAP_M)
    return np.array([*place_xy, place_z])


def rest_centre(release: np.ndarray) -> np.ndarray:
    """Where an object let go with its centre at ``release`` (``place_centre``) comes to rest."""
    return release - RELEASE_GAP_M * UP


def lower_and_release(op: PlanningOperator, item: dict, name: str, offset: np.ndarray, place: np.ndarray,
                      rise_to: float = -np.inf, out: np.ndarray | None = None) -> None:
    """From above ``place`` (the wrist position that lets object ``name`` go where it belongs):
    lower, open, (``out``: first move the open hand by that much, level: a side grasp's fingers
    out from under the part above them), retreat, then on up to wrist height ``rise_to``; before
    lowering, the operator corrects the lower, open and retreat keyframes for how the object has
    slipped. The rise stays where the plan put it: corrected too, frypan_stand_pour fell from 10 to 7/12."""
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    # above the target the operator looks where the object really sits in the hand (it may
    # have slipped while carried) and corrects every later keyframe of this pick for it
    first = len(tl.frames)
    tl.add(DURATIONS["lower"], pos=place)
    tl.add(open_steps(item), hand=side["open"])
    if out is not None:
        place = place + out
        tl.add(DURATIONS["retreat"], pos=place)
    tl.add(DURATIONS["retreat"], pos=place + APPROACH_HEIGHT_M * UP)
    carried_at = tl.frames[first - 1].end_step
    side["corrections"].append((carried_at, name, offset, slice(first, len(tl.frames))))
    if rise_to > tl.frames[-1].pos[2]:
        tl.add(DURATIONS["lift"], pos=np.array([*tl.frames[-1].pos[:2], rise_to]))


def carry_height(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str, offset: np.ndarray) -> float:
    """The lowest wrist height at which the carried object ``name``'s bottom clears the top of the step's
    target by CARRY_CLEARANCE_M: a person lifts a thing over a tall bin's rim before moving it across."""
    if item["place"] == TABLE_TARGET:
        return -np.inf
    task = op.scene.task
    top = op.object_pos(data, item["place"])[2] + task.objects[item["place"]].half_extents[2]
    return float(top + CARRY_CLEARANCE_M + task.objects[name].half_extents[2] - offset[2])


def lift_height(item: dict) -> float:
    """How far a pick lifts its object over the grasp and carries it over the place: `lift_m`, else
    LIFT_HEIGHT_M (jigsaw's yellow piece, 9 cm: carried 14 cm up, the RH56DFX set it out on 2 of 3 seeds)."""
    return LIFT_HEIGHT_M if item.get("lift_m") is None else float(item["lift_m"])


def carry_steps(item: dict) -> int:
    """Control steps of a pick's carry, from the lift to above its place: `carry_s` seconds, else
    DURATIONS["carry"]. A long reach, the hand turning as it goes, takes a person longer; at the
    default second the IIWA7's wrist lagged its plan by up to 0.9 rad carrying a jigsaw piece to the
    far side of the table, and the piece swung out of the fingertips."""
    return steps_of_seconds(item, "carry_s", DURATIONS["carry"])


def open_steps(item: dict) -> int:
    """Control steps a pick's hand takes to open over its place before it rises: `open_s` seconds, else
    DURATIONS["open"]. Fingers wedged on the object open late: the RH56DFX's index and little fingers, either
    side of a 6.4 cm jar held from above, were still closed on it a third of a second after the open began, and
    the rising hand lifted it out of the tray and tipped it over (canned_food_tray_arrangement)."""
    return steps_of_seconds(item, "open_s", DURATIONS["open"])


def steps_of_seconds(item: dict, field: str, default_steps: int) -> int:
    """Control steps of an optional duration field given in seconds (at least one), else ``default_steps``."""
    return default_steps if item.get(field) is None else max(1, round(float(item[field]) * CONTROL_HZ))


def carry_and_place(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str, offset: np.ndarray) -> None:
    """The held object ``name`` (its centre ``offset`` from the wrist) carried from where the hand is to
    the step's `place` at `place_offset`: up over the place's rim, across (over anything in the way),
    lowered and let go; the operator looks where the place is when the hand sets off. The second half
    of a pick, and how a strike puts its tool away."""
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    lifted = tl.frames[-1]
    lifted.pos = np.array([*lifted.pos[:2], max(lifted.pos[2], carry_height(op, data, item, name, offset))])
    place = place_centre(op, data, item, name) - offset
    op.leaves(name, rest_centre(place + offset), on=item["place"])
    carry_frame = len(tl.frames)
    op.set_off(side, data, item, carry_steps(item), pos=place + lift_height(item) * UP, carried=(name, offset))
    lower_frame = len(tl.frames)
    out = None
    if side_roll(item):     # the way the hand came in, back out: along its palm's normal
        held = np.zeros(9)
        mujoco.mju_quat2Mat(held, tl.frames[-1].quat)
        out = -SIDE_GRASP_IN_M * (held.reshape(3, 3) @ PALM_NORMAL)
    lower_and_release(op, item, name, offset, place, out=out)
    if grasp_kind(item) == "flat_pinch":      # looks at it in the hand, squares it, eases the tips apart
        ready = flat_pinch(op, data, item, name)[1]      # the pre-shape it came down with (same data: same plan)
        flat_place(op, data, item, name, offset, carry_frame, lower_frame, ready)
    if item["place"] != TABLE_TARGET:
        op.look_again(side, item["place"], data, carry_frame, len(tl.frames))
