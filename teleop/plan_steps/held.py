"""An object kept in a hand between plan steps: what a `handover` leaves in the hand that took it, and a
`pour` with `hold: true` in the hand that poured.

The operator remembers, per hand, the object held, its centre's offset from the wrist (world) and its
rotation (world), as planned. The next step of that hand naming the object starts from holding it
instead of grasping it: a `pick` carries it to its place at once (or slides it in from the front), a
`pour` carries it to the target and tips it (and sets it down at `place_offset`, or with `hold: true` keeps
it upright over the target). `planner` wraps a step kind's planner so that steps that find nothing held
go on to it unchanged. `pour_held` follows pour.plan (teleop/plan_steps/pour.py) from the grasp on.
"""

from __future__ import annotations

from typing import Callable

import mujoco
import numpy as np

from sim.demo_plan import PLACE_FROM_FRONT, POUR_DEFAULT_GRASP, POUR_DEFAULT_TILT_DEG, SIDE_GRASP, TABLE_TARGET
from sim.errors import SpecError
from teleop.operator_motion import DURATIONS, LIFT_HEIGHT_M, UP, SideTimeline, quat
from teleop.plan_steps.front_place import carry_and_place_front
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.pick_place import (SIDE_GRASP_ROLL_DEG, carry_and_place, grasp_and_lift, lower_and_release,
                                         place_centre, rest_centre)
from teleop.plan_steps.pour import (BOTTOM_ABOVE_RIM_M, MOUTH_ABOVE_RIM_M, POUR_DURATIONS, aim_point, mouth_local,
                                    point_world, tilt_turn, upright_in_hand)
from teleop.transit import CLEARANCE_M, hand_outline


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


def planner(kind: str, plan: Callable) -> Callable:
    """Step kind ``kind``'s (`pick` or `pour`) planner ``plan``, or, for a step naming an object a hand holds
    (or a pour with `hold: true`), this module's, which starts from holding it."""
    held_plan = {"pick": pick_held, "pour": pour_held}[kind]

    def planned(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
        if item[kind] in {name for name, _, _ in op.held.values()} or item.get("hold", False):
            held_plan(op, data, item)
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


def pour_held(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
    """A `pour` of a bottle the hand holds already (else grasped as pour does), and/or kept in the hand
    afterwards (`hold: true`): upright over the target, turned upright by the bottle itself, for the next
    step of the hand (a handover). The tilt is pour's (teleop/plan_steps/pour.py)."""
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    name, target = item["pour"], item["into"]
    obj = op.scene.task.objects[name]
    held = take(op, item, name)
    if held is not None and not item.get("hold", False) and "place_offset" not in item:
        raise SpecError(op.scene.task.source, "demo_plan", "a pour of a bottle the hand holds sets it down at "
                        "place_offset [x, y] of the table (it came from the other hand), or keeps it (hold: true)",
                        item)
    start = op.planned_place(data, name, tl.end)[0]
    if held is None:
        obj_rot = data.xmat[op.scene.object_body_ids[name]].reshape(3, 3).copy()
        roll = 0.0 if item.get("grasp", POUR_DEFAULT_GRASP) != SIDE_GRASP else \
            SIDE_GRASP_ROLL_DEG * (1.0 if item["hand"] == "right" else -1.0)
        offset = grasp_and_lift(op, data, item, name, roll_deg=roll)
    else:
        offset, obj_rot = held
        offset = offset.copy()
    hand_rot = np.zeros(9)
    mujoco.mju_quat2Mat(hand_rot, tl.frames[-1].quat)
    hand_rot = hand_rot.reshape(3, 3)
    axis_local = np.asarray(obj.mouth_axis, float) / np.linalg.norm(obj.mouth_axis)
    if target in op.scene.task.objects:
        top = float(op.planned_place(data, target, tl.end)[0][2] + op.scene.task.objects[target].half_extents[2])
        aim = np.array([*aim_point(op, data, target), top + MOUTH_ABOVE_RIM_M])
    else:
        point = point_world(op, target)
        top = float(point[2])
        aim = np.array([point[0], point[1], top + MOUTH_ABOVE_RIM_M])
    mouth = obj_rot @ mouth_local(obj)

    def wrist_at(T: np.ndarray) -> np.ndarray:
        return aim - T @ (offset + mouth)

    bottom = float(np.abs(obj_rot[2]) @ obj.half_extents)
    q_now = side["kin"].ik(tl.frames[-1].pos, tl.frames[-1].quat, side["q"]).q
    T = tilt_turn(side, hand_rot, obj_rot, axis_local, float(item.get("tilt_deg", POUR_DEFAULT_TILT_DEG)),
                  wrist_at, q_now, item.get("tilt_toward"))
    tipped = wrist_at(T)
    over = tipped.copy()
    over[2] = max(tipped[2], top + BOTTOM_ABOVE_RIM_M + bottom - offset[2])
    carry = len(tl.frames)
    op.set_off(side, data, item, POUR_DURATIONS["to_target"], pos=over, carried=(name, offset))
    tl.add(POUR_DURATIONS["tilt"], pos=tipped, quat=quat(T @ hand_rot))
    tl.add(POUR_DURATIONS["pour"])
    tl.add(POUR_DURATIONS["untilt"], pos=over, quat=quat(hand_rot))
    untilted = len(tl.frames) - 1
    if target in op.scene.task.objects:
        op.look_again(side, target, data, carry, len(tl.frames))
    if item.get("hold", False):
        tl.add(DURATIONS["hold"])           # the look after the untilt turns the bottle upright here
        keep(op, item["hand"], name, offset, obj_rot)
    else:
        spot = {"place": TABLE_TARGET, "place_offset": list(item.get("place_offset", start[:2]))}
        place = place_centre(op, data, spot, name) - offset
        op.leaves(name, rest_centre(place + offset))
        tl.add(POUR_DURATIONS["back"], pos=place + LIFT_HEIGHT_M * UP)
        lowest = float(np.min((hand_outline(side["hand"], item["hand"], side["open"]) @ hand_rot.T)[:, 2]))
        top = place[2] + offset[2] + float(obj.half_extents[2])
        lower_and_release(op, item, name, offset, place, rise_to=top + CLEARANCE_M - lowest)
    op.on_frame_end(side, untilted, upright_in_hand(op, side, name, axis_local, hand_rot, offset,
                                                    range(untilted + 1, len(tl.frames))))

