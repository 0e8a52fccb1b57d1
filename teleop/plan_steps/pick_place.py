"""Plan step `pick`: carry an object to a target (another object, or a spot of the table).

Approach, descend, close, lift, carry, lower, open, retreat; palm down, or with the fingers pitched
down (`approach_pitch_deg`). Where the object sits in the hand and how the hand closes come from
the hand file's palm grasp, or, with `grasp: pinch`, from a pinch found from the hand's kinematics
(teleop/pinch_grasp.py). Where the object goes comes from `place_offset`.
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from sim.demo_plan import TABLE_TARGET
from sim.embodiment.mirror import mirror_vec
from teleop.operator_motion import APPROACH_HEIGHT_M, DURATIONS, LIFT_HEIGHT_M, UP, SideTimeline, pitched_palm_down, quat
from teleop.pinch_grasp import pinch_axis_in_site_frame, pinch_preshape

if TYPE_CHECKING:
    from teleop.scripted_operator import ScriptedOperator

# Power grasp closure per actuator group (early, late), each 0 = open .. 1 = grasp target. Closing:
# the early actuators (fingers) form a wall, then the late ones (thumb) press the object against it.
# Releasing opens both together: a thumb kept in opposition hooks the fruit as the hand lifts and
# flicks it off the plate.
WALL, CLOSED = (1.0, 0.0), (1.0, 1.0)
PINCH_SPREAD_MARGIN_M = 0.025  # pinch pre-shape: pads this much wider apart than the object
RELEASE_GAP_M = 0.005         # lowered to just above the plate: fruit let go higher bounces and rolls
PALM_CLEARANCE_M = 0.004


def place_offset(item: dict) -> np.ndarray:
    """A plan step's `place_offset` (checked when the task loads): [dx, dy] from the target's centre,
    optionally dz from its top (negative: lowered into a container and let go just above its floor
    rather than its rim); for `place: table`, the [x, y] of the table top to set the object down at."""
    return np.array([*item.get("place_offset", [0.0, 0.0]), 0.0][:3], float)


def approach_pitch(item: dict) -> float:
    """A plan step's `approach_pitch_deg`: how far the fingers point down from horizontal (0 = palm
    down, fingers forward). A person tilts the hand for small or low objects so the forearm stays
    clear of the table; a robot arm's wrist links need the same."""
    return float(item.get("approach_pitch_deg", 0.0))


@functools.lru_cache(maxsize=None)
def level_pinch_pitch(hand_name: str) -> float:
    """The finger pitch (degrees, 0..60) that levels the hand's pinch axis, so that the thumb and
    the fingers come down to the same height beside a low object instead of the lower one landing
    on it; 0 where the axis already falls towards the fingers (pitching would only tilt it more)."""
    axis = pinch_axis_in_site_frame(hand_name)
    pitches = np.arange(0.0, 61.0)
    elevation = np.array([(pitched_palm_down(p) @ axis)[2] for p in pitches])
    return float(pitches[np.argmin(np.abs(elevation))]) if elevation[0] > 0 else 0.0


def grasp_kind(item: dict) -> str:
    """A plan step's `grasp`: "power" (the hand's palm grasp, default) or "pinch" (thumb against the
    first fingers' pads, for objects too small for the palm; teleop/pinch_grasp.py)."""
    return item.get("grasp", "power")


def plan(op: ScriptedOperator, data: mujoco.MjData, item: dict) -> None:
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    task = op.scene.task
    offset_xyz = place_offset(item)
    obj = task.objects[item["pick"]]
    half_z = obj.half_extents[2]
    pinch = grasp_kind(item) == "pinch"
    if pinch and "approach_pitch_deg" not in item:
        hand_rot = pitched_palm_down(level_pinch_pitch(side["hand"]))
    else:
        hand_rot = pitched_palm_down(approach_pitch(item))
    hand_quat = quat(hand_rot)
    open_ = side["open"]
    if pinch:
        # come down with the pads spread wider than the object, its centre midway between them
        axis = pinch_axis_in_site_frame(side["hand"])
        axis = hand_rot @ (mirror_vec(axis) if item["hand"] == "left" else axis)
        body_rot = data.xmat[op.scene.object_body_ids[item["pick"]]].reshape(3, 3)
        width = 2.0 * float(np.abs(body_rot.T @ axis) @ obj.half_extents) + PINCH_SPREAD_MARGIN_M
        ready, centre = pinch_preshape(side["hand"], open_, side["pinch_close"], width)
        offset = hand_rot @ (mirror_vec(centre) if item["hand"] == "left" else centre)
        closing = [(DURATIONS["close"] + DURATIONS["close_late"], side["pinch_close"])]
    else:
        # object centre in the wrist-site frame: the hand's grasp centre, lifted clear of the palm
        cx, cy, cz = side["grasp_centre"]
        offset = hand_rot @ np.array([cx, max(cy, half_z + PALM_CLEARANCE_M), cz])
        closing = [(DURATIONS["close"], op.power(side, WALL)), (DURATIONS["close_late"], op.power(side, CLOSED))]
        ready = open_
    grasp = op.object_pos(data, item["pick"]) - offset
    if item["place"] == TABLE_TARGET:       # set down at a spot of the table top
        place_xy = offset_xyz[:2]
        place_z = op.scene.table_height + offset_xyz[2] + obj.rest_height + RELEASE_GAP_M
    else:
        target = task.objects[item["place"]]
        place_xy = op.object_pos(data, item["place"])[:2] + offset_xyz[:2]
        place_z = (op.object_pos(data, item["place"])[2] + target.half_extents[2] + offset_xyz[2]
                   + half_z + RELEASE_GAP_M)
    place = np.array([*place_xy, place_z]) - offset
    reach = len(tl.frames)
    tl.add(DURATIONS["approach"], pos=grasp + APPROACH_HEIGHT_M * UP, quat=hand_quat, hand=ready)
    tl.add(DURATIONS["descend"], pos=grasp)
    for duration, targets in closing:
        tl.add(duration, hand=targets)
    tl.add(DURATIONS["hold"])
    tl.add(DURATIONS["lift"], pos=grasp + LIFT_HEIGHT_M * UP)
    op.look_again(side, item["pick"], data, reach, len(tl.frames))
    carry = len(tl.frames)
    tl.add(DURATIONS["carry"], pos=place + LIFT_HEIGHT_M * UP)
    # above the target the operator looks where the object really sits in the hand (it may
    # have slipped while carried) and corrects every later keyframe of this pick for it
    first = len(tl.frames)
    tl.add(DURATIONS["lower"], pos=place)
    tl.add(DURATIONS["open"], hand=open_)
    tl.add(DURATIONS["retreat"], pos=place + APPROACH_HEIGHT_M * UP)
    carried_at = tl.frames[first - 1].end_step
    side["corrections"].append((carried_at, item["pick"], offset, slice(first, len(tl.frames))))
    if item["place"] != TABLE_TARGET:
        op.look_again(side, item["place"], data, carry, len(tl.frames))
