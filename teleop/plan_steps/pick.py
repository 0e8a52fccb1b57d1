"""Plan step `pick`: grasp and lift (teleop/plan_steps/pick_place.py), then one of three ways to put
the object where it goes: slid in level through the side a container is open at (`place_from: front`,
front_place.py), turned on the way so that an axis points down and lowered that end first
(`place_axis`, axis_place.py), or carried over the target, lowered and let go (pick_place.py).
A hand that has let go stays risen over the place for its next step, unless `return_home: true` (returning())."""

from __future__ import annotations

from typing import Callable

import mujoco

from sim.demo_plan import PLACE_FROM_FRONT
from teleop.plan_steps.axis_place import carry_and_place_axis_down
from teleop.plan_steps.front_place import carry_and_place_front
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.pick_place import SIDE_GRASP_IN_M, carry_and_place, grasp_and_lift, side_roll


def round_pinched(op: PlanningOperator, item: dict) -> dict:
    """The step as planned for its hand: with `round_pinch: true`, where the hand file declares a pinch for a thin
    round object lying on the table (`round_pinch`), a flat pinch of those fingers, the others folded that far. The
    Schunk's own (index alone, the others folded 0.9): the folded ring finger was the hand's lowest point and held
    the thick tips off the table; they met over a 1 cm pen, and the marker, held above its middle, slid out."""
    declared = op.sides[item["hand"]]["round_pinch"] if item.get("round_pinch") else None
    if declared is None:
        return item
    step = {**item, "grasp": "flat_pinch"}
    if declared.fingers is not None:
        step["pinch_fingers"] = list(declared.fingers)
    if declared.fold is not None:
        step["pinch_fold"] = declared.fold
    if declared.tips_height_m is not None:
        step["grasp_tips_height_m"] = declared.tips_height_m
    return step


def plan(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
    roll = side_roll(item)
    offset = grasp_and_lift(op, data, item, item["pick"], roll_deg=roll, side_in_m=SIDE_GRASP_IN_M if roll else 0.0)
    if item.get("place_from") == PLACE_FROM_FRONT:
        carry_and_place_front(op, data, item, item["pick"], offset)
    elif "place_axis" in item:
        carry_and_place_axis_down(op, data, item, item["pick"], offset)
    else:
        carry_and_place(op, data, item, item["pick"], offset)


def as_declared(inner: Callable) -> Callable:
    """The `pick` planner ``inner`` given the step as planned for its hand (round_pinched)."""
    def planned(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
        inner(op, data, round_pinched(op, item))
    return planned


def returning(inner: Callable) -> Callable:
    """The `pick` planner ``inner``, then with `return_home: true` the hand back to its home pose (over what is in
    the way, teleop/transit.py): left risen over a tool box after placing the drill, the right arm met the left
    one carrying the wrench in over the box."""
    def planned(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
        inner(op, data, item)
        if item.get("return_home", False):
            side = op.sides[item["hand"]]
            op.set_off_home(side, data, hand=side["open"])
    return planned
