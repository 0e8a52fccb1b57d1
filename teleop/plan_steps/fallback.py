"""A pick's `fallback`: the step done another way where the embodiment's arm cannot do it as written.

`fallback` {field: value, ...}: the step is planned as written, then checked against the arm: its wrist path,
tracked by the arm's IK from home as the dry run does (warm-started, solved again from home on a miss), strays
more than STRAY_M from the plan during the step, or a `place_axis` turn (teleop/plan_steps/axis_place.py) leaves
an arm joint within TURN_MARGIN_RAD of its limit on the carry. Then the step's plan is taken back and it is
planned with those fields in place of its own. An arm that does the step as written plans it unchanged, bit for
bit. stationery_category_sorting on the Pandas: turning the marker's end down over the cup ran the Panda's wrist
joint 7 into its limit (the stream path 8-9 cm off; the turn keeps 0.02 rad or less; the RM65's every joint 0.47
rad or more inside, seeds 0-11), so its other end goes down; the glue's side grasp turned 45 degrees is reached
only with the wrist flipped (the IK 14-20 cm off; the RM65's at most 5.3 cm, as it lets the glue go), so it is
taken palm down.
"""

from __future__ import annotations

import copy

import mujoco

from sim.demo_plan import step_kind
from teleop.plan_steps import PLANNERS

STRAY_M = 0.10              # the arm's IK further than this off the step's planned wrist path: on another branch
TURN_MARGIN_RAD = 0.2       # a place_axis turn leaving a joint nearer its limit: no room for the look's correction
IK_ITERS = 30               # per control step, warm-started (as ScriptedOperator.act)


def plan_step(op, data: mujoco.MjData, item: dict, sides: list[dict]) -> None:
    """Plan ``item`` (its kind's planner) for its hands' ``sides``, with its `fallback` fields if the arm cannot do
    it as written."""
    if not item.get("fallback"):
        PLANNERS[step_kind(item)](op, data, item)
        return
    saved = _snapshot(op, sides)
    PLANNERS[step_kind(item)](op, data, item)
    if not any(cannot_follow(side, first) for side, first in zip(sides, saved["firsts"])):
        return
    _restore(op, sides, saved)
    done_otherwise = {k: v for k, v in item.items() if k != "fallback"} | item["fallback"]
    PLANNERS[step_kind(done_otherwise)](op, data, done_otherwise)


def cannot_follow(side: dict, first: int) -> bool:
    """Whether ``side``'s arm cannot do its keyframes from ``first`` on as planned: a place_axis turn near a joint
    limit (axis_place.py leaves its margin in ``side["turn_margin"]``), or the tracked IK astray."""
    margin = side.pop("turn_margin", None)
    if margin is not None and margin < TURN_MARGIN_RAD:
        return True
    frames = side["timeline"].frames
    start = frames[first - 1].end_step
    kin, q = side["kin"], side["q_home"].copy()
    for step in range(frames[-1].end_step + 1):
        pos, quat, _ = side["timeline"].at(step)
        result = kin.ik_tracking(pos, quat, q, side["q_home"], max_iters=IK_ITERS)
        q = result.q
        if step >= start and result.pos_err_m > STRAY_M:
            return True
    return False


def _snapshot(op, sides: list[dict]) -> dict:
    """What planning a step changes, to take it back."""
    return {"firsts": [len(s["timeline"].frames) for s in sides],
            "frames": [copy.deepcopy(s["timeline"].frames) for s in sides],
            "lists": [{k: list(s[k]) for k in ("looks", "corrections", "reaims")} for s in sides],
            "q": [s["q"].copy() for s in sides],
            "held": dict(op.held), "link_angles": dict(op.link_angles), "leaving": list(op._leaving)}


def _restore(op, sides: list[dict], saved: dict) -> None:
    for side, frames, lists, q in zip(sides, saved["frames"], saved["lists"], saved["q"]):
        side["timeline"].frames = frames
        side.update(lists)
        side["q"] = q
        side.pop("turn_margin", None)
    op.held, op.link_angles, op._leaving = saved["held"], saved["link_angles"], saved["leaving"]
