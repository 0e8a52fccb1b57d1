"""An object kept in a hand between plan steps: what a `handover` leaves in the hand that took it, and a
`pour` with `hold: true` in the hand that poured.

The operator remembers, per hand, the object held, its centre's offset from the wrist (world) and its
rotation (world), as planned. The next step of that hand naming the object starts from holding it
instead of grasping it: a `pick` carries it to its place at once (or slides it in from the front,
`pick_held`); a `pour` carries it to the target and tips it (pour.plan, which takes it from here).
"""

from __future__ import annotations

from typing import Callable

import mujoco
import numpy as np

from sim.demo_plan import PLACE_FROM_FRONT
from sim.errors import SpecError
from teleop.plan_steps.front_place import carry_and_place_front
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.pick_place import carry_and_place


def keep(op: PlanningOperator, hand: str, name: str, offset: np.ndarray, rotation: np.ndarray) -> None:
    """The step being planned leaves ``name`` in ``hand``, its centre ``offset`` from the wrist (world),
    turned ``rotation`` (world)."""
    op.held[hand] = (name, np.asarray(offset, float), np.asarray(rotation, float))


def take(op: PlanningOperator, item: dict, name: str) -> tuple[np.ndarray, np.ndarray] | None:
    """(offset, rotation) of ``name`` if the step's hand holds it (it lets it go from the operator's memory:
    the step now owns it), else None; a step naming what the other hand holds is refused."""
    for hand, (held, offset, rotation) in list(op.held.items()):
        if held != name:
            continue
        if hand != item["hand"]:
            raise SpecError(op.scene.task.source, "demo_plan", f"a step of the {hand} hand, which holds {name!r} "
                            f"(a handover gives it to the other)", item)
        del op.held[hand]
        return offset, rotation
    return None


def planner(plan: Callable) -> Callable:
    """The `pick` planner ``plan``, or, for a pick of an object a hand holds, ``pick_held``, which starts from
    holding it (a pour of a held bottle is pour.plan's own)."""
    def planned(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
        if item["pick"] in {name for name, _, _ in op.held.values()}:
            pick_held(op, data, item)
        else:
            plan(op, data, item)
    return planned


def pick_held(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
    """A `pick` of an object the hand holds: carried to its place (through the front) and let go."""
    offset, _ = take(op, item, item["pick"])
    if item.get("place_from") == PLACE_FROM_FRONT:
        carry_and_place_front(op, data, item, item["pick"], offset)
    else:
        carry_and_place(op, data, item, item["pick"], offset)

