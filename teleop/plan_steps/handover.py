"""Plan step `handover`: one hand gives an object to the other in the air, as a person passes a bottle
from the hand that took it out of the fridge to the hand that pours.

The giving hand holds the object already (an earlier handover, or a pour with `hold: true`), or picks
it first: from above as `pick` does, or with `pick_from: front` level out of a container open at a side
(teleop/plan_steps/front_pick.py). It carries the object so that its centre is at `at` and holds still.
Meanwhile the taking hand, turned for a side grasp (`take_roll_deg` about its fingers, default thumb up),
comes to beside the object's `take_point` (a part the giver's hand leaves free), out along its palm's
normal. Once the giver is there, the taker looks where that point really is (the object hangs in the
giver's hand lower, or swung), moves in, closes, and only then the giver opens, draws its hand back
along its palm's normal and goes home; the taker holds still until the giver's hand is off. The object
stays in the taking hand for its next step (teleop/plan_steps/held.py).
"""

from __future__ import annotations

import mujoco
import numpy as np

from sim.demo_plan import PLACE_FROM_FRONT
from teleop.operator_motion import DURATIONS, NOT_IN_HAND_M, UP, SideTimeline, quat
from teleop.plan_steps.front_pick import side_hold, take_out_front
from teleop.plan_steps.held import keep, take
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.pick_place import (CLOSED, PALM_NORMAL, SIDE_GRASP_IN_M, SIDE_GRASP_ROLL_DEG, WALL,
                                         grasp_and_lift, side_roll)

HANDOVER_STEPS = 120      # the giver carries the object to the handover point slowly: a heavy bottle swings
BODY_HOLD = "body"        # a hand file's heavy_side_hold that takes a handover's body_hold
LOOK_RANGE_M = 2 * NOT_IN_HAND_M   # the take point found farther than this from its plan: dropped, nothing to take


def at_point(op: PlanningOperator, item: dict) -> np.ndarray:
    """The step's `at` in the world: [x, y] of the table top, z above it."""
    return np.asarray(item["at"], float) + op.scene.table_height * UP


def plan(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
    item = for_the_hand(op, item)
    name = item["handover"]
    giver, taker = op.sides[item["hand"]], op.sides[item["to_hand"]]
    offset, rotation = in_giving_hand(op, data, item, name)
    at = at_point(op, item)
    op.set_off(giver, data, item, HANDOVER_STEPS, pos=at - offset, carried=(name, offset))
    t_offset = taker_closes(op, data, item, name, at, rotation)
    giver_lets_go(op, giver, taker)
    keep(op, item["to_hand"], name, t_offset, rotation)


def for_the_hand(op: PlanningOperator, item: dict) -> dict:
    """The step with its `body_hold` fields in place of its own on an embodiment whose hand carries a heavy
    object round its body (its file's `heavy_side_hold: body`; both sides have the same hand)."""
    if "body_hold" not in item or op.sides[item["to_hand"]]["heavy_side_hold"] != BODY_HOLD:
        return item
    return {**item, **item["body_hold"]}


def in_giving_hand(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str) -> tuple[np.ndarray, np.ndarray]:
    """The object's centre from the giver's wrist (world) and its rotation, as held: where an earlier step left
    it in the hand, or picked now (from above, or out of a container's side opening)."""
    held = take(op, item, name)
    if held is not None:
        return held.offset, held.rotation
    rotation = data.xmat[op.scene.object_body_ids[name]].reshape(3, 3).copy()
    if item.get("pick_from") == PLACE_FROM_FRONT:
        return take_out_front(op, data, item, name), rotation
    roll = side_roll(item)
    return grasp_and_lift(op, data, item, name, roll_deg=roll, side_in_m=SIDE_GRASP_IN_M if roll else 0.0), rotation


def taker_closes(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str, at: np.ndarray,
                 rotation: np.ndarray) -> np.ndarray:
    """Append the taking hand's way to beside the take point (while the giver carries the object to ``at``),
    its wait for the giver, the look, the move in and the closing; return the object centre's offset from
    the taker's wrist (world) as it will hold it."""
    giver, taker = op.sides[item["hand"]], op.sides[item["to_hand"]]
    gtl: SideTimeline = giver["timeline"]
    ttl: SideTimeline = taker["timeline"]
    sign = 1.0 if item["to_hand"] == "right" else -1.0
    point = item.get("take_point", [0.0, 0.0, 0.0])
    t_rot, t_offset = side_hold(op, data, item["to_hand"], name, sign * item.get("take_roll_deg", SIDE_GRASP_ROLL_DEG),
                                point)
    grasp = at - t_offset
    op.set_off(taker, data, item, DURATIONS["approach"], pos=grasp - SIDE_GRASP_IN_M * (t_rot @ PALM_NORMAL),
               quat=quat(t_rot), hand=taker["open"])
    meet = max(gtl.end + DURATIONS["hold"], ttl.end)      # the giver there and still, the taker beside it
    for tl in (gtl, ttl):
        tl.add(meet - tl.end)
    arrived = len(ttl.frames) - 1
    ttl.add(DURATIONS["descend"], pos=grasp)
    ttl.add(DURATIONS["close"], hand=op.power(taker, WALL))
    ttl.add(DURATIONS["close_late"], hand=op.power(taker, CLOSED))
    ttl.add(DURATIONS["hold"])
    planned = at + rotation @ np.asarray(point, float)
    op.on_frame_end(taker, arrived, look_before_taking(op, taker, name, planned, point,
                                                       range(arrived + 1, len(ttl.frames))))
    return t_offset


def giver_lets_go(op: PlanningOperator, giver: dict, taker: dict) -> None:
    """Once the taker has closed, the giver opens, draws back along its palm's normal (out of a side grasp,
    up off one from above) and goes home; the taker holds still until the giver's hand is off the object."""
    gtl: SideTimeline = giver["timeline"]
    ttl: SideTimeline = taker["timeline"]
    gtl.add(ttl.end - gtl.end)
    gtl.add(DURATIONS["open"], hand=giver["open"])
    held_rot = np.zeros(9)
    mujoco.mju_quat2Mat(held_rot, gtl.frames[-1].quat)
    gtl.add(DURATIONS["retreat"], pos=gtl.frames[-1].pos - SIDE_GRASP_IN_M * (held_rot.reshape(3, 3) @ PALM_NORMAL))
    gtl.add(DURATIONS["approach"], pos=giver["home"][0], quat=giver["home"][1])
    ttl.add(gtl.frames[-2].end_step - ttl.end)


def look_before_taking(op: PlanningOperator, taker: dict, name: str, planned: np.ndarray, point, frames: range):
    """The look once the taking hand is beside the object: it hangs in the giver's hand off where it was
    planned (lower, swung about the grasp), so the taking hand's later keyframes of this step (``frames``)
    move with its take point (``point``, object frame; ``planned``: where the plan had it, world)."""
    def adjust(data: mujoco.MjData) -> None:
        body = op.scene.object_body_ids[name]
        moved = op.object_pos(data, name) + data.xmat[body].reshape(3, 3) @ np.asarray(point, float) - planned
        if np.linalg.norm(moved) > LOOK_RANGE_M:
            return
        for frame in taker["timeline"].frames[frames.start:frames.stop]:
            frame.pos = frame.pos + moved
    return adjust
