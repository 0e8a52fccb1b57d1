"""Plan step `press`: press keys or buttons (slide-jointed links "<object>/<link>") in order.

The way a person plays a melody with one finger: the index finger points, the thumb and the other
fingers curl out of the way, and the hand pitches so that the index tip is its lowest point (and
turns in a little, so two hands playing side by side keep their forearms apart). The tip hovers
above each key, goes down past the key's travel, comes back up to the hover height (so a repeated
key is released before it is pressed again: C-C is two presses) and moves on. The pointing shape
and the pitch come from the hand's kinematics, the key's travel and top from its joint and geoms
in the scene: no per-hand or per-task numbers.
"""

from __future__ import annotations

import functools

import mujoco
import numpy as np

from sim.embodiment.mirror import M
from teleop.operator_motion import APPROACH_HEIGHT_M, DURATIONS, UP, SideTimeline, pitched_palm_down, quat, yawed
from teleop.pinch_grasp import fingertip_rows, hand_kinematics
from teleop.plan_steps.operator import PlanningOperator


FOLD_FRACTION = 0.9          # the fingers that do not point: this far towards their closed end
PITCH_RANGE_DEG = (20.0, 80.0)   # candidate finger pitches (fingers down from horizontal)
CLEARANCE_M = 0.035          # the rest of the hand this far above the index tip: clear of the
                             # neighbouring keys with the key pressed its full travel
YAW_IN_DEG = 20.0            # fingers turned in towards the body's midline, the forearms out to
                             # their own side: two hands playing close together keep their arms apart
HOVER_M = 0.02               # index tip this far above a key's top between presses
OVERSHOOT_M = 0.003          # ... and this far past the key's full travel when pressing
MOVE_STEPS = 30              # hover to hover, one key to the next (0.5 s)
PRESS_STEPS = 18             # down (0.3 s)
HOLD_STEPS = 10              # held down
RELEASE_STEPS = 15           # back up to the hover height; the key's spring returns it


def _index_finger(hand_name: str) -> tuple[int, str]:
    """Row (in ``fingertips_in_site_frame``) and finger name of the pointing finger: the one whose
    retarget point follows the index fingertip."""
    [row] = fingertip_rows(hand_name, ("index_tip",))
    return row, hand_kinematics(hand_name).spec.fingertips[row].finger


def _lowest(kin, links, down_site: np.ndarray) -> np.ndarray:
    """The lowest point (furthest along ``down_site``, wrist-site frame) of the geoms of ``links``
    at the configuration last set on ``kin``."""
    site = kin.hand.wrist_site
    best, best_d = None, -np.inf
    for link in links:
        body = kin.model.body(link.name).id
        R, p = kin.data.xmat[body].reshape(3, 3), kin.data.xpos[body]
        u = R.T @ (site.rot @ down_site)                    # site -> hand base -> link frame
        for geom in link.geoms:
            point = site.to_local(p + R @ geom.support(u))
            if point @ down_site > best_d:
                best, best_d = point, point @ down_site
    return best


@functools.lru_cache(maxsize=None)
def pointing(hand_name: str) -> tuple[np.ndarray, np.ndarray, float]:
    """The pointing hand (right): actuator targets (the actuators that move the index tip at home,
    the rest folded), the lowest point of the index finger in the wrist-site frame, and the finger
    pitch (degrees): the least at which every other part of the hand is CLEARANCE_M above that
    point (a person points no steeper than needed), else the one that clears them most."""
    kin = hand_kinematics(hand_name)
    row, finger = _index_finger(hand_name)
    moving = np.zeros(kin.dof, bool)
    for q in (kin.home, kin.mid):
        _, J = kin.points_and_jacobians(q)
        moving |= np.abs(J[1 + row]).sum(axis=0) > 1e-9         # rows of kin.points: wrist first
    far = np.where(np.abs(kin.upper - kin.home) >= np.abs(kin.lower - kin.home), kin.upper, kin.lower)
    q = np.where(moving, kin.home, kin.home + FOLD_FRACTION * (far - kin.home))
    kin.points(q)                                               # sets the configuration
    index = [link for link in kin.hand.links if link.finger == finger]
    rest = [link for link in kin.hand.links if link.finger != finger]
    best = (-np.inf, None, None)
    for pitch in np.arange(PITCH_RANGE_DEG[0], PITCH_RANGE_DEG[1] + 1.0):
        down = pitched_palm_down(pitch).T @ -UP                # world down in the site frame
        tip = _lowest(kin, index, down)
        clearance = tip @ down - _lowest(kin, rest, down) @ down
        if clearance > best[0]:
            best = (clearance, tip, float(pitch))
        if clearance >= CLEARANCE_M:
            break
    q.flags.writeable = best[1].flags.writeable = False         # cached: shared by every caller
    return q, best[1], best[2]


def key_geometry(model: mujoco.MjModel, data: mujoco.MjData, name: str) -> tuple[np.ndarray, np.ndarray, float]:
    """The point of key ``name`` to press (centre of its geoms, on their top surface against the
    press), the press direction (world unit vector along the slide towards the far end of its
    range from rest) and the travel (m) from rest to that end."""
    joint = model.joint(name)
    body = int(joint.bodyid[0])
    lo, hi = model.jnt_range[joint.id]
    rest = float(data.qpos[model.jnt_qposadr[joint.id]])
    end = lo if abs(lo - rest) >= abs(hi - rest) else hi
    axis = data.xmat[body].reshape(3, 3) @ model.jnt_axis[joint.id]
    press = axis * np.sign(end - rest)
    centres, tops = [], []
    for g in range(model.body_geomadr[body], model.body_geomadr[body] + model.body_geomnum[body]):
        R = data.geom_xmat[g].reshape(3, 3)
        centre = data.geom_xpos[g] + R @ model.geom_aabb[g, :3]
        centres.append(centre)
        tops.append(float(-press @ centre + np.abs(R.T @ press) @ model.geom_aabb[g, 3:]))
    centre = np.mean(centres, axis=0)
    point = centre - press * (press @ centre + max(tops))     # moved against the press onto the top
    return point, press, abs(end - rest)


def plan(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    q, index, pitch = pointing(side["hand"])
    point_hand = np.clip(q, *op.scene.model.actuator_ctrlrange[side["hand_ids"]].T)
    if item["hand"] == "left":
        index = index @ M           # M is its own transpose: mirrored
    yaw_in = np.radians(YAW_IN_DEG) * (1.0 if item["hand"] == "right" else -1.0)   # the right's fingers turn to -x
    hand_rot = yawed(pitched_palm_down(pitch), yaw_in)
    tip = hand_rot @ index                       # index tip from the wrist site, world
    for k, name in enumerate(item["press"]):
        top, press, travel = key_geometry(op.scene.model, data, name)
        hover = top - press * HOVER_M - tip
        down = top + press * (travel + OVERSHOOT_M) - tip
        first = len(tl.frames)
        if k == 0:
            op.set_off(side, data, item, DURATIONS["approach"], pos=hover + APPROACH_HEIGHT_M * UP, quat=quat(hand_rot),
                       hand=point_hand)
            tl.add(DURATIONS["descend"], pos=hover)
        else:
            tl.add(MOVE_STEPS, pos=hover)
        tl.add(PRESS_STEPS, pos=down)
        tl.add(HOLD_STEPS)
        tl.add(RELEASE_STEPS, pos=hover)
        if k == len(item["press"]) - 1:     # up off the last key, from wherever it turns out to be
            tl.add(DURATIONS["retreat"], pos=hover + APPROACH_HEIGHT_M * UP)
        # a free object (a mouse) may have been nudged or carried since: look where it is on setting
        # off for the key
        op.look_again(side, name.split("/")[0], data, first, len(tl.frames))
