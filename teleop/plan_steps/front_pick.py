"""`pick_from: front`: take an upright object out of a container open at a side (a bottle out of a
fridge) the way a person does: not from above, where the container's top is, but level through the
opening.

The hand, turned for a side grasp (palm towards the object, thumb up), comes level to just outside the
opening, slides in to beside the object, moves in along its palm's normal until the palm is just short
of the part at the grasp point, closes, lifts the object off the floor as far as the cavity's ceiling
lets the hand rise, and slides it straight back out until the object and the hand are clear of the
opening. The opening comes from the container's walls (teleop/plan_steps/front_place.py).
"""

from __future__ import annotations

import mujoco
import numpy as np

from sim.errors import SpecError
from teleop.operator_motion import DURATIONS, UP, SideTimeline, pitched_palm_down, quat, yawed
from teleop.plan_steps.front_place import CEILING_GAP_M, OUTSIDE_M, SLIDE_STEPS, side_opening
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.pick_place import (PALM_NORMAL, SIDE_GRASP_IN_M, approach_pitch, grasp_point, power_closing,
                                         side_grasp_offset, side_roll, turned_about_fingers)
from teleop.transit import bounding_box_points, hand_outline

TAKE_LIFT_M = 0.02      # lifted this far off the cavity floor before it slides out (less under a low ceiling)


def side_hold(op: PlanningOperator, data: mujoco.MjData, hand: str, name: str, roll_deg: float, point,
              pitch_deg: float = 0.0, yaw_deg: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """A side grasp of object ``name`` by ``hand`` at ``point`` (object frame), as `pick`'s `grasp: side`
    closes (teleop/plan_steps/pick_place.py): the hand rotation (world) and the object centre's offset
    from the wrist site (world), the palm just short of the part there. The object's shape is read where
    it is now; the offset holds wherever it is, turned the same way."""
    hand_rot = yawed(turned_about_fingers(pitched_palm_down(pitch_deg), roll_deg), np.radians(yaw_deg))
    at = data.xmat[op.scene.object_body_ids[name]].reshape(3, 3) @ np.asarray(point, float)
    return hand_rot, side_grasp_offset(op, data, op.sides[hand], name, hand_rot, at)


def container_of(op: PlanningOperator, data: mujoco.MjData, name: str, step: int) -> str:
    """The container object ``name`` is in at control step ``step``: where an earlier step left it, else
    the one whose cavity holds its centre now."""
    on = op.planned_place(data, name, step)[1]
    if on is not None:
        return on
    pos = op.object_pos(data, name)
    for other, obj in op.scene.task.objects.items():
        if obj.interior_half_extents is None or other == name:
            continue
        body = op.scene.object_body_ids[other]
        R = data.xmat[body].reshape(3, 3)
        local = R.T @ (pos - data.xpos[body]) - np.asarray(obj.interior_offset, float)
        if np.all(np.abs(local) <= np.asarray(obj.interior_half_extents, float)):
            return other
    raise SpecError(op.scene.task.source, "demo_plan.pick_from", "an object inside a container open at a side", name)


def take_out_front(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str) -> np.ndarray:
    """Append the hand's way in through the opening of the container ``name`` stands in, the side grasp
    (the step's grasp_point, grasp_roll_deg, approach_pitch_deg, grasp_yaw in degrees), the lift off the
    floor and the slide back out; return the object centre's offset from the wrist (world) as held."""
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    model = op.scene.model
    way = side_opening(op, data, container_of(op, data, name, tl.end), side["home"][0],
                       rays_at=float(op.object_pos(data, name)[2]))      # the compartment it stands in
    hand_rot, offset = side_hold(op, data, item["hand"], name, side_roll(item), grasp_point(item),
                                 approach_pitch(item), float(item.get("grasp_yaw", 0.0)))
    grasp = op.object_pos(data, name) - offset
    beside = grasp - SIDE_GRASP_IN_M * (hand_rot @ PALM_NORMAL)
    open_pts = hand_outline(side["hand"], item["hand"], side["open"]) @ hand_rot.T
    closed_pts = hand_outline(side["hand"], item["hand"], side["open"], side["closed"]) @ hand_rot.T
    body_pts = bounding_box_points(model, data, op.scene.object_body_ids[name]) - op.object_pos(data, name) + offset

    def clear_of_mouth(wrist: np.ndarray, pts: np.ndarray) -> float:
        """How far out along the opening the wrist moves so that ``pts`` (from it) are OUTSIDE_M clear."""
        return max(0.0, float((wrist - way.mouth) @ -way.out) + float(np.max(pts @ -way.out)) + OUTSIDE_M)

    reach = len(tl.frames)
    op.set_off(side, data, item, DURATIONS["approach"], pos=beside + clear_of_mouth(beside, open_pts) * way.out,
               quat=quat(hand_rot), hand=side["open"])
    tl.add(SLIDE_STEPS, pos=beside)
    tl.add(DURATIONS["descend"], pos=grasp)
    for duration, targets, _ in power_closing(op, side, item):
        tl.add(duration, hand=targets)
    tl.add(DURATIONS["hold"])
    room = way.ceiling - CEILING_GAP_M - float(grasp[2] + closed_pts[:, 2].max())
    lifted = grasp + float(np.clip(room, 0.0, TAKE_LIFT_M)) * UP
    tl.add(DURATIONS["lift"], pos=lifted)
    out = clear_of_mouth(lifted, np.concatenate([closed_pts, body_pts]))
    tl.add(SLIDE_STEPS, pos=lifted + out * way.out)
    op.look_again(side, name, data, reach, len(tl.frames))
    return offset
