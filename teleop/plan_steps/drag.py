"""Plan step `drag`: pull a container across the table into a zone.

The way a person pulls a box or a bowl towards themselves: the hand, palm down and fingers pointing
into the container over the wall on the side it is to go, curls its fingers (the power grasp's early
actuators) to hook them inside that wall, draws the container until its centre is over the zone's
centre, opens and rises. Palm down keeps the arm in the configuration it already has.
"""

from __future__ import annotations


import mujoco
import numpy as np

from sim.demo_plan import DRAG_HOOK_DEPTH_M, DRAG_PITCH_DEG
from sim.embodiment.mirror import M
from sim.errors import SpecError
from sim.scene.sample import zone_centre
from teleop.geom_rays import body_geoms, nearest_hit
from teleop.operator_motion import APPROACH_HEIGHT_M, DURATIONS, UP, SideTimeline, pitched_palm_down, quat, yawed
from teleop.pinch_grasp import fingertip_rows, fingertips_in_site_frame
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.pick_place import WALL


DRAG_INSET_M = 0.015          # curled fingertips this far inside the leading wall
DRAG_SPEED_M_PER_STEP = 0.0025  # 0.15 m/s


def plan(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    obj = op.scene.task.objects[item["drag"]]
    body = op.scene.object_body_ids[item["drag"]]
    centre = data.xpos[body].copy()
    goal = zone_centre(op.scene.task.zones[item["to_zone"]]) + np.asarray(item.get("place_offset", (0.0, 0.0)))
    way = goal - centre[:2]
    distance = float(np.linalg.norm(way))
    if distance < 1e-6:
        return
    d = np.array([*(way / distance), 0.0])
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


def wall_distance(op: PlanningOperator, data: mujoco.MjData, body: int, point: np.ndarray, d: np.ndarray) -> float:
    """How far the container's own wall is from ``point`` (inside it) along ``d``: a ray against
    each of its geoms, so a round bowl and a box both come out exact."""
    model = op.scene.model
    dist = nearest_hit(model, data, body_geoms(model, body), point, d)
    if dist is None:
        raise SpecError(op.scene.task.source, "demo_plan.drag", "a container whose walls surround its centre",
                        f"no wall of {model.body(body).name} along {np.round(d, 3).tolist()}")
    return dist
