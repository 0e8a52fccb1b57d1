"""An object kept in a hand between plan steps: what a `handover` leaves in the hand that took it, a `pour`
with `hold: true` in the hand that poured, a `pick` with `hold: true` in the hand that carried it.

The operator remembers, per hand, one `HeldObject`: the object, its centre's offset from the wrist (world)
and its rotation (world), as planned, and for a pick's hold the grasp it was taken with and the frames of
its look at the object in the hand. The next step of that hand naming the object starts from holding it
instead of grasping it: a `pick` carries it to its place at once (or slides it in from the front,
`pick_held`; teleop/plan_steps/via.py's for a hold's); a `pour` carries it to the target and tips it
(pour.plan, which takes it from here).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import mujoco
import numpy as np

from sim.demo_plan import PLACE_FROM_FRONT
from sim.errors import SpecError
from teleop.plan_steps.front_place import carry_and_place_front
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.pick_place import carry_and_place


@dataclass
class HeldObject:
    name: str
    offset: np.ndarray          # its centre from the wrist (world), as planned
    rotation: np.ndarray        # its rotation (world), as planned
    grasp: dict = field(default_factory=dict)   # a pick's hold: the grasp fields it was taken with (let go so)
    settle: list[int] | None = None     # a pick's hold: the frames [first, stop) its look in the hand moves


def keep(op: PlanningOperator, hand: str, name: str, offset: np.ndarray, rotation: np.ndarray, *,
         grasp: dict | None = None, settle: list[int] | None = None) -> None:
    """The step being planned leaves ``name`` in ``hand``, its centre ``offset`` from the wrist (world),
    turned ``rotation`` (world); a pick's hold also says how it was grasped and which frames look at it."""
    op.held[hand] = HeldObject(name, np.asarray(offset, float), np.asarray(rotation, float), dict(grasp or {}),
                               settle)


def take(op: PlanningOperator, item: dict, name: str) -> HeldObject | None:
    """What the step's hand holds if it is ``name`` (the operator lets it go from its memory: the step now
    owns it), else None; a step naming what the other hand holds is refused."""
    for hand, held in list(op.held.items()):
        if held.name != name:
            continue
        if hand != item["hand"]:
            raise SpecError(op.scene.task.source, "demo_plan", f"a step of the {hand} hand, which holds {name!r} "
                            f"(a handover gives it to the other)", item)
        return op.held.pop(hand)
    return None


def kept_by_hold(op: PlanningOperator, hand: str, name: str) -> bool:
    """Whether ``hand`` holds ``name`` as a pick's `hold: true` left it."""
    held = op.held.get(hand)
    return held is not None and held.name == name and held.settle is not None


def planner(plan: Callable) -> Callable:
    """The `pick` planner ``plan``, or, for a pick of an object a hand holds, ``pick_held``, which starts from
    holding it (a pour of a held bottle is pour.plan's own)."""
    def planned(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
        if item["pick"] in {held.name for held in op.held.values()}:
            pick_held(op, data, item)
        else:
            plan(op, data, item)
    return planned


def pick_held(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
    """A `pick` of an object the hand holds: carried to its place (through the front) and let go."""
    offset = take(op, item, item["pick"]).offset
    if item.get("place_from") == PLACE_FROM_FRONT:
        carry_and_place_front(op, data, item, item["pick"], offset)
    else:
        carry_and_place(op, data, item, item["pick"], offset)

