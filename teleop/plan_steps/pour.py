"""Plan step `pour`: pick up a pourer, tip its mouth over a target, tilt it back and set it down.

The way a person pours from a bottle: grasp it (by default from the side, thumb up; or from above
as `pick` does, teleop/plan_steps/pick_place.py), lift it, hold it upright above the target, then
turn the forearm (pronation or supination: a turn about the fingers' heading, the wrist's roomiest
rotation) until the mouth axis is `tilt_deg` from vertical, the wrist placed so that the mouth (the
point the evaluator's `tilted_over` measures: the bounding box surface along the object's
`mouth_axis`) is over the target (an object, or a task point such as a bowl's centre); hold, turn
back upright, carry it to where it came from (or to `place_offset` on the table) and set it down. Which way to turn is chosen with the arm's IK: a turn
that is reached, the palm ending under the pourer (a hand holds best what rests in it), else the
smaller joint motion. `grasp_yaw` and `grasp_point` place the grasp as for `pick`. Turned back, the
operator looks at how the pourer now sits in the hand and turns it upright by the pourer itself
(teleop/plan_steps/upright_look.py); let go, the open hand rises clear of its top before it moves on.
"""

from __future__ import annotations


import mujoco
import numpy as np

from evaluation.geometry import axis_extent
from sim.demo_plan import POUR_DEFAULT_GRASP, POUR_DEFAULT_TILT_DEG, SIDE_GRASP, TABLE_TARGET
from sim.scene.reach import PALM_DOWN
from sim.errors import SpecError
from teleop.operator_motion import DURATIONS, LIFT_HEIGHT_M, NOT_IN_HAND_M, UP, SideTimeline, axis_rotation, quat
from teleop.plan_steps.held import keep, take
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.pick_place import (PALM_NORMAL, SIDE_GRASP_ROLL_DEG, grasp_and_lift, lower_and_release,
                                         place_centre, planned_top, rest_centre)
from teleop.plan_steps.upright_look import upright_look
from teleop.transit import CLEARANCE_M, hand_outline


FINGERS_PALM_DOWN = PALM_DOWN.T @ np.array([0.0, 1.0, 0.0])   # the fingers' direction, wrist-site frame
MOUTH_ABOVE_RIM_M = 0.05      # the tipped mouth this high above the target's top: pours in, touches nothing
BOTTOM_ABOVE_RIM_M = 0.04     # carried upright over the target, the pourer's bottom clears its top by this
RIM_INSET_M = 0.03            # the aim stays this far inside a container's cavity walls
TILT_STEP_DEG = 1.0           # resolution of the turn that reaches the wanted tilt
POUR_DURATIONS = {"to_target": 70, "tilt": 70, "pour": 70, "untilt": 70, "back": 120}


def mouth_local(obj) -> np.ndarray:
    """The pourer's mouth point in its frame, as the evaluator's `tilted_over` takes it."""
    axis = np.asarray(obj.mouth_axis, float)
    axis = axis / np.linalg.norm(axis)
    return axis * axis_extent(axis, obj.half_extents)


def aim_point(op: PlanningOperator, data: mujoco.MjData, name: str) -> np.ndarray:
    """Where (xy) the mouth goes: the target's origin (what `tilted_over` measures from), moved
    inside its cavity's walls when it has one, so that what is poured lands in it."""
    obj = op.scene.task.objects[name]
    body = op.scene.object_body_ids[name]
    origin = data.xpos[body].copy()
    if obj.interior_half_extents is None:
        return origin[:2]
    R = data.xmat[body].reshape(3, 3)
    centre = np.asarray(obj.interior_offset, float)
    room = np.maximum(np.asarray(obj.interior_half_extents, float)[:2] - RIM_INSET_M, 0.0)
    local = centre.copy()
    local[:2] += np.clip(-centre[:2], -room, room)      # origin, relative to the cavity centre, clipped
    return (origin + R @ local)[:2]


def point_world(op: PlanningOperator, name: str) -> np.ndarray:
    """A task point in the world: its z is from the table top, as the evaluator resolves it
    (sim/tasks.py task_context: every task point is table-relative)."""
    return np.asarray(op.scene.task.points[name], float) + op.scene.table_height * UP


def tilt_turn(side: dict, hand_rot: np.ndarray, obj_rot: np.ndarray, axis_local: np.ndarray,
              tilt_deg: float, wrist_at, q_seed: np.ndarray, toward=None) -> np.ndarray:
    """The world rotation of the hand that tips the pourer's mouth axis ``tilt_deg`` from vertical:
    a turn about the fingers' (level) heading, whichever way the arm's IK reaches (``wrist_at(R)`` gives the
    wrist position for turn R), preferring the palm under the pourer, then the smaller joint motion from
    ``q_seed``. ``toward`` ([dx, dy], optional): only a turn that tips the mouth that way."""
    # the fingers' heading, levelled: a hand pitched down turns about it (forearm plus wrist) so
    # that the mouth can tip past horizontal; palm down it is the fingers' direction itself
    fingers = hand_rot @ FINGERS_PALM_DOWN
    fingers = np.array([fingers[0], fingers[1], 0.0]) / np.linalg.norm(fingers[:2])
    best = None
    for sign in (1.0, -1.0):
        for deg in np.arange(0.0, 180.0 + TILT_STEP_DEG, TILT_STEP_DEG):
            T = axis_rotation(fingers, sign * np.radians(deg))
            up = T @ obj_rot @ axis_local
            if np.degrees(np.arccos(np.clip(up[2], -1.0, 1.0))) >= tilt_deg:
                break
        else:
            continue
        if toward is not None and float(up[:2] @ np.asarray(toward, float)) <= 0.0:
            continue
        result = side["kin"].ik(wrist_at(T), quat(T @ hand_rot), q_seed)
        # reached first; then the pourer lying in the palm rather than hanging from the fingers
        # (a hand's grip is weakest pulled open), then the smaller joint motion
        palm_up = float((T @ hand_rot @ PALM_NORMAL)[2])
        key = (not result.success, -round(palm_up, 3), float(np.abs(result.q - q_seed).sum()))
        if best is None or key < best[0]:
            best = (key, T)
    if best is None:        # only a pourer lying far off upright in the hand could miss it
        raise ValueError(f"pour: no turn about the fingers tips the mouth axis {tilt_deg:g} degrees"
                         + (f" towards {list(toward)}" if toward is not None else ""))
    return best[1]


def plan(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    name, target = item["pour"], item["into"]
    obj = op.scene.task.objects[name]
    holding = take(op, item, name)      # handed over by the other hand: poured from the hand, not grasped
    if holding is None:
        start = op.object_pos(data, name)
        obj_rot = data.xmat[op.scene.object_body_ids[name]].reshape(3, 3).copy()
        grasp = item.get("grasp", POUR_DEFAULT_GRASP)
        roll = 0.0 if grasp != SIDE_GRASP else SIDE_GRASP_ROLL_DEG * (1.0 if item["hand"] == "right" else -1.0)
        offset = grasp_and_lift(op, data, item, name, roll_deg=roll)     # object centre from the wrist, as held
    elif item.get("hold", False) or "place_offset" in item:
        start, offset, obj_rot = None, holding.offset.copy(), holding.rotation
    else:
        raise SpecError(op.scene.task.source, "demo_plan", "a pour of a bottle the hand holds sets it down at "
                        "place_offset [x, y] of the table (it came from the other hand), or keeps it (hold: true)",
                        item)
    hand_rot = np.zeros(9)
    mujoco.mju_quat2Mat(hand_rot, tl.frames[-1].quat)
    hand_rot = hand_rot.reshape(3, 3)
    axis_local = np.asarray(obj.mouth_axis, float) / np.linalg.norm(obj.mouth_axis)
    if target in op.scene.task.objects:
        # the target's top where earlier steps leave it (the operator re-aims in xy when it sets off,
        # but heights come from the plan)
        top = planned_top(op, data, target, tl.end)[1]
        aim = np.array([*aim_point(op, data, target), top + MOUTH_ABOVE_RIM_M])
    else:       # a task point: the mouth straight above it, as high above it as above a rim
        point = point_world(op, target)
        top = float(point[2])
        aim = np.array([point[0], point[1], top + MOUTH_ABOVE_RIM_M])
    mouth = obj_rot @ mouth_local(obj)                   # object centre -> mouth, upright as grasped

    def wrist_at(T: np.ndarray) -> np.ndarray:           # the held pourer turned by T, its mouth at aim
        return aim - T @ (offset + mouth)

    # upright above the pour pose, its bottom clear of the target's top
    bottom = float(np.abs(obj_rot[2]) @ obj.half_extents)
    q_lift = side["kin"].ik(tl.frames[-1].pos, tl.frames[-1].quat, side["q"]).q
    T = tilt_turn(side, hand_rot, obj_rot, axis_local, float(item.get("tilt_deg", POUR_DEFAULT_TILT_DEG)),
                  wrist_at, q_lift, item.get("tilt_toward"))
    tipped = wrist_at(T)
    over = tipped.copy()
    over[2] = max(tipped[2], top + BOTTOM_ABOVE_RIM_M + bottom - offset[2])
    carry = len(tl.frames)
    if holding is None:
        tl.add(POUR_DURATIONS["to_target"], pos=over)
    else:       # from where the handover left it: around whatever stands between
        op.set_off(side, data, item, POUR_DURATIONS["to_target"], pos=over, carried=(name, offset))
    tl.add(POUR_DURATIONS["tilt"], pos=tipped, quat=quat(T @ hand_rot))
    tl.add(POUR_DURATIONS["pour"])
    if holding is not None:     # handed over: it sits in this hand as the giver left it, not as planned
        op.on_frame_end(side, len(tl.frames) - 3, mouth_over_target(op, side, name, target, offset + mouth,
                                                                    range(len(tl.frames) - 2, len(tl.frames))))
    tl.add(POUR_DURATIONS["untilt"], pos=over, quat=quat(hand_rot))
    untilted = len(tl.frames) - 1
    if target in op.scene.task.objects:     # an object may have been nudged since; a point stays put
        op.look_again(side, target, data, carry, len(tl.frames))
    if item.get("hold", False):     # kept upright over the target for the hand's next step (a handover)
        tl.add(DURATIONS["hold"])   # the look after the untilt turns the bottle upright here
        keep(op, item["hand"], name, offset, obj_rot)
    else:
        set_down(op, data, item, name, offset, hand_rot, start)
    op.on_frame_end(side, untilted, upright_look(op, side, name, axis_local, hand_rot, offset,
                                                 range(untilted + 1, len(tl.frames)), recentre_when_upright=False))


def mouth_over_target(op: PlanningOperator, side: dict, name: str, target: str, planned: np.ndarray, frames: range):
    """The look before tipping a bottle another hand gave: it hangs in this hand leaning or lower than
    planned (``planned``: the mouth from the wrist, world, as the handover planned it), so its mouth would
    miss the target. A person looks where the mouth is in their hand and moves the hand so that, tipped
    (``frames``: the tilt and its hold), the mouth comes over the target (where it is now; level moves only)."""
    obj = op.scene.task.objects[name]

    def adjust(data: mujoco.MjData) -> None:
        body = op.scene.object_body_ids[name]
        wrist_rot = data.site_xmat[side["wrist_site_id"]].reshape(3, 3)
        mouth = data.xpos[body] + data.xmat[body].reshape(3, 3) @ mouth_local(obj)
        in_hand = wrist_rot.T @ (mouth - data.site_xpos[side["wrist_site_id"]])
        if np.linalg.norm(in_hand) > np.linalg.norm(planned) + NOT_IN_HAND_M:      # not in the hand any more
            return
        aim = aim_point(op, data, target) if target in op.scene.task.objects else point_world(op, target)[:2]
        R = np.zeros(9)
        for frame in side["timeline"].frames[frames.start:frames.stop]:
            mujoco.mju_quat2Mat(R, frame.quat)
            miss = aim - (frame.pos + R.reshape(3, 3) @ in_hand)[:2]
            frame.pos = frame.pos + np.array([miss[0], miss[1], 0.0])
    return adjust


def set_down(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str, offset: np.ndarray,
             hand_rot: np.ndarray, start: np.ndarray | None) -> None:
    """Back down at place_offset of the table, else where it came from (``start``), and let go."""
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    obj = op.scene.task.objects[name]
    spot = {"place": TABLE_TARGET, "place_offset": list(item["place_offset"] if "place_offset" in item else start[:2])}
    place = place_centre(op, data, spot, name) - offset
    op.leaves(name, rest_centre(place + offset))
    tl.add(POUR_DURATIONS["back"], pos=place + LIFT_HEIGHT_M * UP)
    # the open hand rises clear of the bottle's top before it moves away: held from the side, the
    # hand is beside the bottle and lower than its top, and a move across would sweep it over
    lowest = float(np.min((hand_outline(side["hand"], item["hand"], side["open"]) @ hand_rot.T)[:, 2]))
    top = place[2] + offset[2] + float(obj.half_extents[2])
    lower_and_release(op, item, name, offset, place, rise_to=top + CLEARANCE_M - lowest)


