"""Plan step `drag`: pull a container across the table into a zone.

The way a person pulls a box or a bowl towards themselves: the hand, palm down and fingers pointing
into the container over the wall on the side it is to go, curls its fingers (the power grasp's early
actuators) to hook them inside that wall, draws the container until its centre is over the zone's
centre, opens and rises. Palm down keeps the arm in the configuration it already has.

With `contact: palm`, the way a person slides a mug along a counter under a tap: the open hand
upright on its edge, palm towards the way, fingers level across it and thumb up, its lowest edge
just above the table, comes down behind the container on the far side of its way and pushes it there,
its foremost point on the line through the container's centre. A tall narrow container (no room
inside for curled fingers, tipped by a pull at its rim) slides upright, and the hand stays below
what overhangs the goal (a spout); what lies on the container (a spoon across its rim) rides along.
"""

from __future__ import annotations


import mujoco
import numpy as np

from sim.demo_plan import DRAG_HOOK_DEPTH_M, DRAG_PALM, DRAG_PITCH_DEG
from sim.embodiment.mirror import M
from sim.errors import SpecError
from sim.scene.sample import zone_centre
from teleop.geom_rays import body_geoms, nearest_hit
from teleop.operator_motion import APPROACH_HEIGHT_M, DURATIONS, UP, SideTimeline, pitched_palm_down, quat, yawed
from teleop.pinch_grasp import THUMB_TIP, fingertip_rows, fingertips_in_site_frame
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.palm_push import palm_frame
from teleop.plan_steps.pick_place import WALL
from teleop.transit import hand_outline


DRAG_INSET_M = 0.015          # curled fingertips this far inside the leading wall
DRAG_SPEED_M_PER_STEP = 0.0025  # 0.15 m/s
PUSH_TIP_HEIGHT_M = 0.015     # contact: palm: the hand's lowest edge this far above the table
PUSH_GAP_M = 0.06             # ... set down this far behind the wall (clear of what overhangs it), then pushing
PUSH_APPROACH_M = 0.2         # ... coming down from this far above the set-down
PUSH_SPEED_M_PER_STEP = 0.0015  # 0.09 m/s: a round container pushed briskly turns off the fingers
RAY_BACKOFF_M = 0.5           # the ray finding the wall's outside starts this far behind the container


def _way(op: PlanningOperator, item: dict, centre: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """A container's spot in the step's zone (place_offset from the zone's centre), the level unit
    direction from its centre there, and the distance."""
    goal = zone_centre(op.scene.task.zones[item["to_zone"]]) + np.asarray(item.get("place_offset", (0.0, 0.0)))
    way = goal - centre[:2]
    distance = float(np.linalg.norm(way))
    return goal, np.array([*(way / max(distance, 1e-12)), 0.0]), distance


def plan(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
    if item.get("contact") == DRAG_PALM:
        return push(op, data, item)
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    obj = op.scene.task.objects[item["drag"]]
    body = op.scene.object_body_ids[item["drag"]]
    centre = data.xpos[body].copy()
    _, d, distance = _way(op, item, centre)
    if distance < 1e-6:
        return
    # fingers point at -d: PALM_DOWN's fingers (+y) turned about z
    hand_rot = yawed(pitched_palm_down(item.get("pitch_deg", DRAG_PITCH_DEG)), np.arctan2(-d[1], -d[0]) - np.pi / 2)
    hooked = op.power(side, np.multiply(WALL, item.get("hook_closure", 1.0)))   # 1: the full wall hook
    tips = fingertips_in_site_frame(side["hand"], hooked)[fingertip_rows(side["hand"])]   # the fingers, not the thumb
    if item["hand"] == "left":
        tips = tips @ M             # M is its own transpose: each row mirrored
    hook_tip = hand_rot @ tips.mean(axis=0)                         # curled fingertips from the site
    target = np.array([*centre[:2], centre[2] + obj.half_extents[2] - item.get("hook_depth", DRAG_HOOK_DEPTH_M)])
    target += d * (wall_distance(op, data, body, target, d) - DRAG_INSET_M)
    start = target - hook_tip
    end = start + d * distance
    reach = len(tl.frames)
    op.set_off(side, data, item, DURATIONS["approach"], pos=start + APPROACH_HEIGHT_M * UP, quat=quat(hand_rot),
               hand=side["open"])
    op.leaves(item["drag"], centre + d * distance)
    tl.add(DURATIONS["descend"], pos=start)
    op.look_again(side, item["drag"], data, reach, len(tl.frames))
    tl.add(DURATIONS["close"], hand=hooked)
    tl.add(int(max(DURATIONS["carry"], distance / DRAG_SPEED_M_PER_STEP)), pos=end)
    tl.add(DURATIONS["close"], hand=side["open"])
    tl.add(DURATIONS["retreat"], pos=end + APPROACH_HEIGHT_M * UP)


def push(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
    """`contact: palm`: the flat hand, palm towards the way and thumb up, pushes the container from
    behind (above); its lowest edge just above the table, so the push acts along the wall's whole foot."""
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    name = item["drag"]
    body = op.scene.object_body_ids[name]
    centre = op.planned_place(data, name, tl.end)[0]     # where an earlier step (an earlier push) leaves it
    goal, d, distance = _way(op, item, centre)
    if distance < 1e-6:
        return
    R = push_frame(side, item["hand"], d)
    outline = hand_outline(side["hand"], item["hand"], side["open"]) @ R.T      # world-aligned, from the site
    low = float(outline[:, 2].min())
    # the hand's foremost point along the way: it meets the wall, so it goes on the line through the
    # container's centre (a round one pushed off that line slides along the palm)
    foremost = outline[int(np.argmax(outline @ d))]
    front = float(foremost @ d)
    aside = foremost - front * d
    aside[2] = 0.0
    now = data.xpos[body]
    # the wall's outside behind the centre, at the height of the hand's lowest edge: a ray at the
    # container as it is now, moved to where it is planned to be
    height = op.scene.table_height + PUSH_TIP_HEIGHT_M
    origin = np.array([*(now[:2] - d[:2] * RAY_BACKOFF_M), height])
    hit = nearest_hit(op.scene.model, data, body_geoms(op.scene.model, body), origin, d)
    if hit is None:
        raise SpecError(op.scene.task.source, "demo_plan.drag", "a container with a wall at its foot to push",
                        op.scene.model.body(body).name)
    wall = origin + hit * d + np.array([*(centre[:2] - now[:2]), 0.0])
    site = np.array([*(wall[:2] - front * d[:2] - aside[:2]), height - low])     # the hand's front on the wall
    start, end = site - PUSH_GAP_M * d, site + distance * d
    # the operator looks again as the hand sets off and moves the set-down by how far the container is
    # from where it is now (``now``), not from where it is planned: set down relative to ``now``
    start_now = start + np.array([*(now[:2] - centre[:2]), 0.0])
    reach = len(tl.frames)
    # from high enough over the set-down that the hand, turning on its way there, clears what is in or
    # on the container (the transit leaves the pushed container and its load to the step)
    above = start_now + PUSH_APPROACH_M * UP
    op.set_off(side, data, item, DURATIONS["approach"], pos=above, quat=quat(R), hand=side["open"])
    op.leaves(name, np.array([*goal, centre[2]]))
    tl.add(DURATIONS["descend"], pos=start_now)
    op.look_again(side, name, data, reach, len(tl.frames))
    tl.add(int(max(DURATIONS["carry"], (distance + PUSH_GAP_M) / PUSH_SPEED_M_PER_STEP)), pos=end)
    tl.add(DURATIONS["retreat"], pos=end - PUSH_GAP_M * d)
    tl.add(DURATIONS["lift"], pos=end - PUSH_GAP_M * d + APPROACH_HEIGHT_M * UP)


def push_frame(side: dict, hand: str, d: np.ndarray) -> np.ndarray:
    """The wrist-site rotation of a flat hand pushing along ``d`` (horizontal): the palm square to it,
    the fingers level across it and the thumb up, as a person slides a cup along a counter."""
    thumb = fingertips_in_site_frame(side["hand"], side["open"])[fingertip_rows(side["hand"], (THUMB_TIP,))[0]]
    if hand == "left":
        thumb = M @ thumb
    across = np.cross(UP, d)
    frames = [palm_frame(d, sign * across) for sign in (1.0, -1.0)]
    return max(frames, key=lambda R: float((R @ thumb)[2]))


def wall_distance(op: PlanningOperator, data: mujoco.MjData, body: int, point: np.ndarray, d: np.ndarray) -> float:
    """How far the container's own wall is from ``point`` (inside it) along ``d``: a ray against
    each of its geoms, so a round bowl and a box both come out exact."""
    model = op.scene.model
    dist = nearest_hit(model, data, body_geoms(model, body), point, d)
    if dist is None:
        raise SpecError(op.scene.task.source, "demo_plan.drag", "a container whose walls surround its centre",
                        f"no wall of {model.body(body).name} along {np.round(d, 3).tolist()}")
    return dist
