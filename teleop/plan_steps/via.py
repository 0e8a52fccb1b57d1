"""`pick` with waypoints (`via`) and/or kept in the hand (`hold: true`).

A person ladling soup holds the ladle by its handle, dips its bowl into the pot, brings it over the
bowl, and again; meanwhile the other hand holds the bowl up beside the pot. So a pick may take the
carried object's `via_point` (object frame, default its centre: a ladle's bowl) through stops, in order,
`via_times` rounds, before it goes to `place`: `inside: <container>` puts the point over the cavity's
centre, VIA_INSIDE_DEPTH_M below the rim; `over: <object>` puts it above the object, the carried object's
lowest point VIA_OVER_CLEARANCE_M above the object's top. Between stops the hand rises until the carried
object clears every stop's top, moves across level, and comes down; the hand keeps the grasp's turn
throughout (nothing is tipped). When it sets off for a stop the operator looks where that object is now
(a bowl held in the other hand sits where that hand holds it, not quite where it was planned); after the
last stop it turns the object back to how it stood when picked, by the object itself (upright_look.py:
a ladle swings in a pinch), before setting it down.
`hold: true` carries the object to its place and keeps it there in the hand instead of letting go
(teleop/plan_steps/held.py): the hand's next step naming it starts from holding it (a `pick` carries it
on to its place, let go as it was taken). Once it is lifted, and again when that next step starts, the
operator looks where it sits in the hand (a wide bowl taken from the side is pulled ~8 cm along the palm
as the fingers close) and moves the hand so that it goes where planned. A pick of an object the hand
already holds skips the grasp.
"""

from __future__ import annotations

from typing import Callable

import mujoco
import numpy as np

from sim.demo_plan import PLACE_FROM_FRONT
from sim.scene.parts import parts_aabb
from teleop.operator_motion import DURATIONS, LIFT_HEIGHT_M, UP, SideTimeline
from teleop.plan_steps import held
from teleop.plan_steps.front_place import carry_and_place_front
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.pick_place import (SIDE_GRASP_IN_M, carry_and_place, carry_height, grasp_and_lift,
                                         place_centre, planned_top, side_roll)
from teleop.plan_steps.upright_look import upright_look

VIA_INSIDE_DEPTH_M = 0.025      # `inside`: the via point this far below the container's rim (a ladle's bowl dipped in)
VIA_OVER_CLEARANCE_M = 0.03     # `over` and between stops: the carried object's lowest point this far above a top
LIFTED_M = 0.01                 # an object this far above where it rested is in the hand (settle_in_hand)
GRASP_FIELDS = ("grasp", "grasp_roll_deg", "grasp_point", "grasp_yaw", "approach_pitch_deg")
VIA_DURATIONS = {"across": 100, "down": 60, "stay": 30, "up": 60}


def _corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])


def stop_point(op: PlanningOperator, data: mujoco.MjData, stop: dict, step: int,
               below: float) -> tuple[str, np.ndarray]:
    """The stop's object and where the via point goes (world), ``below``: how far the carried object's
    lowest point is under the via point as held."""
    kind = "inside" if "inside" in stop else "over"
    name = stop[kind]
    pos, top = planned_top(op, data, name, step)
    if kind == "inside":        # over the cavity's centre (its box may sit off the object's centre), below the rim
        obj = op.scene.task.objects[name]
        rot = data.xmat[op.scene.object_body_ids[name]].reshape(3, 3)
        point = np.array([*(pos + rot @ np.asarray(obj.interior_offset, float))[:2], top - VIA_INSIDE_DEPTH_M])
    else:
        point = np.array([pos[0], pos[1], top + VIA_OVER_CLEARANCE_M + below])
    offset = np.array([*stop.get("offset", [0.0, 0.0]), 0.0][:3], float)
    return name, point + offset


def follow(op: PlanningOperator, side: dict, name: str, planned_xy: np.ndarray, frames: slice) -> Callable:
    """The look when the hand sets off for a stop: frames ``frames`` move (level) with where object ``name``
    is now rather than where the plan had it."""
    def adjust(data: mujoco.MjData) -> None:
        moved = np.array([*(op.object_pos(data, name)[:2] - planned_xy), 0.0])
        for frame in side["timeline"].frames[frames]:
            frame.pos = frame.pos + moved
    return adjust


def through_stops(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str, offset: np.ndarray,
                  rotation: np.ndarray) -> None:
    """The held object ``name`` (its centre ``offset`` from the wrist, turned ``rotation``, world) taken
    through the step's `via` stops, `via_times` rounds; the hand ends above the last stop, clear of it."""
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    lo, hi = parts_aabb(op.scene.task.objects[name].parts)
    point = rotation @ np.asarray(item.get("via_point", [0.0, 0.0, 0.0]), float)    # centre -> via point
    below = float(point[2] - (_corners(lo, hi) @ rotation.T)[:, 2].min())
    stops = [stop_point(op, data, stop, tl.end, below) for stop in item["via"]]
    tops = [planned_top(op, data, stop_name, tl.end)[1] for stop_name, _ in stops]
    # the travel height: the carried object's lowest point clear of every stop's top
    travel = max(tops) + VIA_OVER_CLEARANCE_M + below - point[2] - offset[2]
    travel = max(travel, float(tl.frames[-1].pos[2]))
    last = tl.frames[-1].pos
    tl.add(VIA_DURATIONS["up"], pos=np.array([last[0], last[1], travel]))
    for _ in range(int(item.get("via_times", 1))):
        for stop_name, at in stops:
            wrist = at - point - offset
            first = len(tl.frames)
            tl.add(VIA_DURATIONS["across"], pos=np.array([wrist[0], wrist[1], travel]))
            tl.add(VIA_DURATIONS["down"], pos=wrist)
            tl.add(VIA_DURATIONS["stay"])
            tl.add(VIA_DURATIONS["up"], pos=np.array([wrist[0], wrist[1], travel]))
            planned_xy = planned_top(op, data, stop_name, tl.end)[0][:2]
            op.on_frame_end(side, first - 1, follow(op, side, stop_name, planned_xy, slice(first, len(tl.frames))))


def settle_in_hand(op: PlanningOperator, side: dict, name: str, offset: np.ndarray, frames: list[int],
                   rest_z: float) -> Callable:
    """The look once the object is lifted: where it sits in the hand now (a wide bowl taken from the side is
    pulled along the palm as the fingers close). Frames ``frames``, planned for it at ``offset`` from the
    wrist, move (level) so that it goes where planned (``frames``: [first, stop), the stop filled in once
    they are planned), and ``offset`` becomes where it sits (a later slip correction measures against
    it). Nothing moves if it was not lifted."""
    planned = offset.copy()

    def adjust(data: mujoco.MjData) -> None:
        body = op.scene.object_body_ids[name]
        if data.xpos[body][2] < rest_z + LIFTED_M:      # not in the hand: nothing to look at
            return
        actual = data.xpos[body] - data.site_xpos[side["wrist_site_id"]]
        error = np.array([*(actual - planned)[:2], 0.0])
        for frame in side["timeline"].frames[frames[0]:frames[1]]:
            frame.pos = frame.pos - error
        offset[:] = actual
    return adjust


def hold_over_place(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str, offset: np.ndarray,
                    rotation: np.ndarray) -> None:
    """The held object carried to the step's place (as a pick lowers it to be let go) and kept there in the
    hand: the hand's next step naming it starts from here."""
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    lifted = tl.frames[-1]
    lifted.pos = np.array([*lifted.pos[:2], max(lifted.pos[2], carry_height(op, data, item, name, offset))])
    place = place_centre(op, data, item, name) - offset
    op.leaves(name, place + offset, on=None)
    first = len(tl.frames)
    op.set_off(side, data, item, DURATIONS["carry"], pos=place + LIFT_HEIGHT_M * UP, carried=(name, offset))
    tl.add(DURATIONS["lower"], pos=place)
    tl.add(DURATIONS["hold"])
    bounds = [first, len(tl.frames)]    # the hand's next pick of it extends them over the wait until it starts
    rest_z = float(op.object_pos(data, name)[2])
    op.on_frame_end(side, first - 1, settle_in_hand(op, side, name, offset, bounds, rest_z))
    held.keep(op, item["hand"], name, offset, rotation, grasp={k: item[k] for k in GRASP_FIELDS if k in item},
              settle=bounds)


def _closing(frames, first: int) -> int | None:
    """Index of the first frame from ``first`` on in which the hand closes (or opens) with the wrist still."""
    return next((k for k in range(max(first, 1), len(frames)) if np.allclose(frames[k].pos, frames[k - 1].pos)
                 and not np.allclose(frames[k].hand, frames[k - 1].hand)), None)


def open_clear(side: dict, first: int, ready: np.ndarray) -> None:
    """The step's release (from frame ``first`` on) opens the hand only to ``ready``, the pre-shape it came
    down with, and fully once it has risen clear: opened fully beside a standing ladle's handle, the
    fingers knocked it over."""
    tl: SideTimeline = side["timeline"]
    k = _closing(tl.frames, first)
    if k is None:
        return
    for frame in tl.frames[k:]:
        frame.hand = ready.copy()
    tl.add(DURATIONS["open"], hand=side["open"])


def plan(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
    """A pick with `via` stops and/or `hold: true` (from holding the object, if the hand does)."""
    name = item["pick"]
    side = op.sides[item["hand"]]
    holding = held.take(op, item, name)
    settle = None           # this step's frames that follow where a kept object sits in the hand: [first, stop)
    ready = None            # a pinch's pre-shape, to let go to
    if holding is None:
        roll = side_roll(item)
        reach = len(side["timeline"].frames)
        offset = grasp_and_lift(op, data, item, name, roll_deg=roll, side_in_m=SIDE_GRASP_IN_M if roll else 0.0)
        rotation = data.xmat[op.scene.object_body_ids[name]].reshape(3, 3).copy()
        k = _closing(side["timeline"].frames, reach)
        if item.get("grasp") == "pinch" and k is not None:
            ready = side["timeline"].frames[k - 1].hand.copy()
    else:
        offset, rotation = holding.offset, holding.rotation
        by_hold = holding.settle is not None
        side["timeline"].add(DURATIONS["hold"])     # a frame of its own for the carry to raise (not the hold's)
        if by_hold:             # the hold's look moves the frames up to here too (the wait for `after`), the
            # carry's own frame with them: left where the hold was planned, the hand jumped back by the look's
            # correction (8 cm on a rim-pinched bowl) as the carry set off, and the bowl fell out
            holding.settle[1] = len(side["timeline"].frames)
            item = {**holding.grasp, **item}    # let go as it was taken (a side grasp moves out along the palm's normal)
        if by_hold:             # where it sits in the hand now, before it moves on
            settle = [len(side["timeline"].frames), None]
            op.on_frame_end(side, settle[0] - 1, settle_in_hand(op, side, name, offset, settle,
                                                                float(op.object_pos(data, name)[2])))
    tl: SideTimeline = side["timeline"]
    if "via" in item:
        through_stops(op, data, item, name, offset, rotation)
    last_stop = len(tl.frames) - 1
    if item.get("hold", False):
        hold_over_place(op, data, item, name, offset, rotation)
    elif item.get("place_from") == PLACE_FROM_FRONT:
        carry_and_place_front(op, data, item, name, offset)
    else:
        release = len(tl.frames)
        carry_and_place(op, data, item, name, offset)
        if ready is not None and "via" in item:
            open_clear(side, release, ready)
    if "via" in item:       # swung in the hand on the way (a ladle in a pinch): set down standing as it stood
        hand_rot = np.zeros(9)
        mujoco.mju_quat2Mat(hand_rot, tl.frames[last_stop].quat)
        op.on_frame_end(side, last_stop, upright_look(op, side, name, rotation.T @ UP, hand_rot.reshape(3, 3), offset,
                                                      range(last_stop + 1, len(tl.frames)), recentre_when_upright=False))
    if settle is not None:
        settle[1] = len(side["timeline"].frames)


def planner(inner: Callable) -> Callable:
    """The `pick` planner: this module's for a pick with `via` or `hold: true`, or of what a `hold: true`
    left in the hand, else ``inner``."""
    def planned(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
        if "via" in item or item.get("hold", False) or held.kept_by_hold(op, item["hand"], item["pick"]):
            plan(op, data, item)
        else:
            inner(op, data, item)
    return planned
