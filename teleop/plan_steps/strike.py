"""Plan step `strike`: pick up a tool, strike a target once with it, put the tool away.

A person taps a block with a hammer: they pick the hammer up by its handle, hold its head a hand's
breadth above the block, swing it down through the block's top (the block stops it), come back up,
then lay the hammer where it belongs. The part that hits is the step's `strike_point` (tool frame);
where it sits relative to the wrist comes from the grasp (the tool keeps its orientation in the
hand), so the swing is aimed by the strike point, not by the wrist. The pick and the put-away are
the `pick` step's (teleop/plan_steps/pick_place.py), grasps included: a tool lying flat whose handle
no palm grasp gets round (screwdriver_box_hammer's 0.6 kg hammer, its handle 6 mm off the table) is
taken with `grasp: flat_pinch` at its balance point (`grasp_point`), and swung level.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from sim.physics import CONTROL_HZ
from teleop.operator_motion import DURATIONS, SMOOTHSTEP_PEAK, UP, SideTimeline
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.pick_place import carry_and_place, grasp_and_lift


STRIKE_RISE_M = 0.08          # the strike point this far above the target's top before the swing
STRIKE_FOLLOW_M = 0.08        # ... aimed this far below it: contact comes mid-swing, at full speed
STRIKE_PEAK_SPEED_M_S = 1.6   # the swing's peak (a tap; the arm lags its target, the evaluator wants ~1)


def swing_steps(distance: float) -> int:
    """Control steps of a smoothstep swing over ``distance`` metres peaking at STRIKE_PEAK_SPEED_M_S."""
    return max(1, math.ceil(SMOOTHSTEP_PEAK * distance / STRIKE_PEAK_SPEED_M_S * CONTROL_HZ))


def strike_point(item: dict) -> np.ndarray:
    """A strike step's `strike_point` [x, y, z] (tool frame, metres): the part of the tool that hits."""
    return np.asarray(item["strike_point"], float)


def plan(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    tool, target = item["tool"], item["strike"]
    task = op.scene.task
    body_rot = data.xmat[op.scene.object_body_ids[tool]].reshape(3, 3)
    # the pick (grasp_point, grasp_yaw, approach_pitch_deg as for `pick`); the tool's centre sits
    # `offset` from the wrist and keeps the orientation it lay in, so its strike point sits `head`
    offset = grasp_and_lift(op, data, item, tool)
    head = offset + body_rot @ strike_point(item)
    top = op.planned_place(data, target, tl.end)[0].copy()     # where earlier steps leave it
    top[2] += task.objects[target].half_extents[2]
    ready = top + STRIKE_RISE_M * UP - head
    first = len(tl.frames)
    op.set_off(side, data, item, DURATIONS["carry"], pos=ready, carried=(tool, offset))
    tl.add(DURATIONS["hold"])                       # steady over the target before the swing
    down = STRIKE_RISE_M + STRIKE_FOLLOW_M
    tl.add(swing_steps(down), pos=ready - down * UP)
    tl.add(DURATIONS["lift"], pos=ready)            # back up, clear of the target
    op.look_again(side, target, data, first, len(tl.frames))   # it may have been nudged since planning
    carry_and_place(op, data, item, tool, offset)      # then away as a pick
