"""`place_axis` on a `pick`: turn the held object on the way so that one of its axes points straight
down, then lower it, that end first, into its place, as a person stands a marker lying on the desk up
in a pen cup: picked up, turned in the fingers while carried, lowered into the cup and let go.

The hand turns by the smallest rotation that takes the object's `place_axis` (its frame) to the
vertical, pointing down, and then about the vertical as far as the arm needs to reach the place (the
least turn for which the arm's IK reaches the release and the pose above it). It turns while it
carries the object over the place; there the object's lower end is CLEAR_M above the target's top, and it is
lowered straight down and let go with that end `place_offset`'s dz from the target's top (negative:
that far into a container). Once lifted the operator looks how the object really sits in the hand
and turns the hand by what the object itself is off, as a pour turns a bottle back upright
(teleop/plan_steps/pour.py).

stationery_category_sorting__rm65_revo2, stream path, seeds 0-11: the marker (flat pinch at its
middle, place_offset dz -0.05) ends upright in the cup on 12 of 12 (8-24 degrees off vertical, leaning
on the cup's wall). Turned more slowly (100-150 steps) it sank in the pinch and toppled over the rim on
1-5 of 6.

`place_either_end: true` lets the object stand on either end: where turning `place_axis` down would run the
hand into its own arm at the place (kinematic check, teleop/plan_steps/own_arm.py), the other end goes down.
On the UR5+Schunk the marker's turn put the thumb's base 4-5 cm into the forearm (the wrist stopped 10 cm
short of the cup); its other end down keeps clear. The RM65+Revo2's keeps clear either way: unchanged.

`place_tilt_deg` stops the turn that many degrees short of straight down: the object is let go leaning
and the container's wall stands it up as it drops in. The 5 mm gray pen, flat-pinched 1.5 cm from its
end, turns with the hand but slips out of the two tips as the turn nears vertical (at 11-18 degrees,
before it is over the cup); turned to 40 degrees short and let go 5 cm into the cup it ended upright
(11-23 degrees off vertical) on 12 of 12 seeds on an earlier host, 11 of 12 on this one (seed 0 across the
rim); turned to 50 degrees short (stop 36) it leaves the tips 24-29 degrees off vertical, 12 of 12.
"""

from __future__ import annotations

import mujoco
import numpy as np

from sim.demo_plan import TABLE_TARGET
from sim.embodiment.frames import quat_to_mat
from teleop.operator_motion import DURATIONS, NOT_IN_HAND_M, UP, SideTimeline, axis_rotation, quat, slerp
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.own_arm import OWN_ARM_DEPTH_M, into_own_arm
from teleop.plan_steps.pick_place import CARRY_CLEARANCE_M, RELEASE_GAP_M, lower_and_release, place_offset, planned_top

DOWN = -UP
CLEAR_M = 0.03          # turned and above its place, the object's lower end this far above the target's top
YAW_STEP_DEG = 15.0     # turns about the vertical tried for a hand pose the arm reaches
MARGIN_POINTS = (24, 5)     # turn_margin: the carry and the lowering, checked at this many poses each
FULL_TURN_SLACK_RAD = 0.01   # turn_margin: a joint range this much over a full turn counts as more than one


def turn_down(direction: np.ndarray, hand_rot: np.ndarray, short_deg: float = 0.0) -> np.ndarray:
    """The smallest rotation (world) that takes unit ``direction`` to straight down (``short_deg``: to
    that many degrees short of it); an axis pointing straight up turns over about the hand's own
    lateral axis (``hand_rot``'s x)."""
    turn = np.cross(direction, DOWN)
    angle = float(np.arctan2(np.linalg.norm(turn), direction @ DOWN)) - np.radians(short_deg)
    if angle < 1e-9:
        return np.eye(3)
    if np.linalg.norm(turn) < 1e-9:
        lateral = hand_rot[:, 0] - (hand_rot[:, 0] @ UP) * UP
        return axis_rotation(lateral / np.linalg.norm(lateral), angle)
    return axis_rotation(turn / np.linalg.norm(turn), angle)


def _about_vertical(deg: float) -> np.ndarray:
    return axis_rotation(UP, np.radians(deg))


def reached_turn(side: dict, T: np.ndarray, hand_rot: np.ndarray, offset: np.ndarray, release: np.ndarray,
                 rise: float, q_seed: np.ndarray) -> np.ndarray:
    """``T`` turned further about the vertical (the object's axis stays down) by the least angle for
    which the arm's IK reaches the wrist that lets the object go at ``release`` and ``rise`` above it;
    none reached: the turn that comes closest."""
    best = None
    for deg in sorted(np.arange(-180.0, 180.0, YAW_STEP_DEG), key=abs):
        turn = _about_vertical(deg) @ T
        wrist, q = release - turn @ offset, quat(turn @ hand_rot)
        low = side["kin"].ik(wrist, q, q_seed)
        high = side["kin"].ik(wrist + rise * UP, q, low.q)
        miss = max(low.miss, high.miss)
        if miss <= 1.0:
            return turn
        if best is None or miss < best[0]:
            best = (miss, turn)
    return best[1]


def turn_margin(side: dict, turn: np.ndarray, hand_rot: np.ndarray, offset: np.ndarray, release: np.ndarray,
                rise: float, q_seed: np.ndarray) -> float:
    """How near (rad) an arm joint comes to its limit as the arm, from ``q_seed`` (lifted), carries the object
    turned ``turn`` above its release and lowers it there (the IK warm-started along the way): a pick's
    `fallback` (teleop/plan_steps/fallback.py) takes over where a turn leaves no room for the look's correction."""
    kin = side["kin"]
    start, start_quat = kin.fk(q_seed)
    place = release - turn @ offset
    above, turned = place + rise * UP, quat(turn @ hand_rot)
    carry, lower = MARGIN_POINTS
    poses = [(start + s * (above - start), slerp(start_quat, turned, s)) for s in np.linspace(0.0, 1.0, carry + 1)]
    poses += [(above + s * (place - above), turned) for s in np.linspace(0.0, 1.0, lower + 1)[1:]]
    # a joint that turns more than a full turn (the UR5's wrists, +-2 pi) is not cornered at a limit: the same pose
    # lies a turn back (counted, the UR5's marker turn fell back on every seed and lost the RH5DG2 two of three)
    bounded = kin.upper - kin.lower <= 2 * np.pi + FULL_TURN_SLACK_RAD
    q, margin = np.asarray(q_seed, float), np.inf
    for pos, q_wxyz in poses:
        q = kin.ik(pos, q_wxyz, q, max_iters=30).q
        room = np.minimum(q - kin.lower, kin.upper - q)[bounded]
        margin = min(margin, float(np.min(room, initial=np.inf)))
    return margin


def tilt_deg(item: dict) -> float:
    """A pick's `place_tilt_deg`: its `place_axis` is left that many degrees short of straight down,
    leaning (0: straight down). A thin pen in a two-tip pinch slips out as the turn nears vertical
    (stationery_category_sorting: at 11-18 degrees); let go leaning into a pen cup, the cup's wall
    stands it up as it drops in."""
    return float(item.get("place_tilt_deg") or 0.0)


def axis_local(item: dict) -> np.ndarray:
    axis = np.asarray(item["place_axis"], float)
    return axis / np.linalg.norm(axis)


def carry_and_place_axis_down(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str,
                              offset: np.ndarray) -> None:
    """The held object ``name`` (its centre ``offset`` from the wrist, world, as planned at the lift)
    turned on the way so that its `place_axis` points down, carried over the step's `place`, lowered
    and let go (the second half of a pick with `place_axis`)."""
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    task = op.scene.task
    obj = task.objects[name]
    axis = axis_local(item)
    hand_rot = quat_to_mat(tl.frames[-1].quat)        # as lifted
    obj_rot = data.xmat[op.scene.object_body_ids[name]].reshape(3, 3)   # held as it lies now
    half = float(np.abs(axis) @ obj.half_extents)     # its half length along the vertical once turned
    at = place_offset(item)
    if item["place"] == TABLE_TARGET:
        xy, top = at[:2], op.scene.table_height
    else:
        target, top = planned_top(op, data, item["place"], tl.end)
        xy = target[:2] + at[:2]
    release = np.array([*xy, top + at[2] + half + RELEASE_GAP_M])    # the object's centre as it is let go
    rise = max(0.0, -at[2]) + CLEAR_M       # lowered from where its lower end is CLEAR_M above the top
    q_lift = side["kin"].ik(tl.frames[-1].pos, tl.frames[-1].quat, side["q"]).q

    def turned_down(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """The turn taking ``axis`` down, the arm's turn with it, and how deep that runs the hand into its arm."""
        down = turn_down(obj_rot @ axis, hand_rot, tilt_deg(item))
        T = reached_turn(side, down, hand_rot, offset, release, rise, q_lift)
        wrist, q = release - T @ offset, quat(T @ hand_rot)
        clash = into_own_arm(op, data, side, [(wrist + rise * UP, q), (wrist, q)], q_lift) \
            if item.get("place_either_end") else 0.0
        return down, T, clash

    down, T, clash = turned_down(axis)
    if clash > OWN_ARM_DEPTH_M:          # place_either_end: the other end down, if that runs less into the arm
        other = turned_down(-axis)
        if other[2] < clash:
            axis, (down, T, clash) = -axis, other
    if item.get("fallback"):        # how near the turn comes to a joint limit, for the step's fallback check
        side["turn_margin"] = turn_margin(side, T, hand_rot, offset, release, rise, q_lift)
    yaw = T @ down.T                            # the turn about the vertical that the arm needs
    turned = T @ offset                         # the object's centre from the wrist once turned
    place = release - turned                                     # the wrist there
    above = place + rise * UP
    # lifted high enough that the turned object's lower end clears the target's top on the way; turned
    # while carried (turned slower, in 100-150 steps, or where it was before the carry, the marker sank in the
    # pinch and toppled over the rim)
    lifted = tl.frames[-1]
    lifted.pos = np.array([*lifted.pos[:2], max(lifted.pos[2], top + CARRY_CLEARANCE_M + half - turned[2])])
    op.leaves(name, release - RELEASE_GAP_M * UP, on=None if item["place"] == TABLE_TARGET else item["place"])
    carry_frame = len(tl.frames)
    op.set_off(side, data, item, DURATIONS["carry"], pos=above, quat=quat(T @ hand_rot), carried=(name, turned))
    held = turned.copy()        # lower_and_release's slip check measures against it: updated by the look below
    lower_and_release(op, item, name, held, place)
    if item["place"] != TABLE_TARGET:
        op.look_again(side, item["place"], data, carry_frame, len(tl.frames))
    op.on_frame_end(side, carry_frame - 1, _as_it_sits(op, side, name, axis, hand_rot, yaw, held,
                                                       range(carry_frame, len(tl.frames)), tilt_deg(item)))


def _as_it_sits(op: PlanningOperator, side: dict, name: str, axis: np.ndarray, hand_rot: np.ndarray,
                yaw: np.ndarray, held: np.ndarray, frames: range, short_deg: float = 0.0):
    """The look once lifted: the turn and the carry's keyframes (``frames``) for how the object really
    sits in the hand; ``held`` (the turned object's centre from the wrist) is updated in place."""
    def adjust(data: mujoco.MjData) -> None:
        body = op.scene.object_body_ids[name]
        wrist_rot = data.site_xmat[side["wrist_site_id"]].reshape(3, 3)
        in_hand = wrist_rot.T @ data.xmat[body].reshape(3, 3)
        at = wrist_rot.T @ (data.xpos[body] - data.site_xpos[side["wrist_site_id"]])
        if np.linalg.norm(at) > np.linalg.norm(held) + NOT_IN_HAND_M:      # not in the hand
            return
        T = yaw @ turn_down(hand_rot @ in_hand @ axis, hand_rot, short_deg)
        now = T @ hand_rot @ at
        moved = held - now          # each keyframe was the wrist for `held`; now for where it sits
        for frame in side["timeline"].frames[frames.start:frames.stop]:
            frame.pos, frame.quat = frame.pos + moved, quat(T @ hand_rot)
        held[:] = now
    return adjust
