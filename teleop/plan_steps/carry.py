"""Plan step `carry`: both hands carry an object too heavy for one (`hand: both`).

The way a person carries a heavy jug with both hands: the palms come down on opposite sides of it,
facing each other (thumbs up, fingers pointing away from the body, turned in a little), across the
object's horizontal axis nearest the line between the two arms (each hand stays on its own side),
at `grasp_height` above its centre (above its centre of mass it hangs between them rather than
tipping out). The palms press in (the squeeze holds the weight by friction), both lift it clear of
the target, carry it over, lower it to `place_offset` (as `pick`'s), let go, move apart and rise;
with `return_home`, both then go back to their home poses.
Both hands' timelines start together (teleop/scripted_operator.py waits for both to be free) and
their keyframes share the same steps, so the object is never pulled apart.
"""

from __future__ import annotations


import mujoco
import numpy as np

from sim.embodiment.description import HandDescription, load_embodiment
from sim.scene.reach import PALM_DOWN
from teleop.operator_motion import (APPROACH_HEIGHT_M, DURATIONS, FORWARD, LIFT_HEIGHT_M, UP, SideTimeline,
                                    axis_rotation, quat, yawed)
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.pick_place import place_centre, rest_centre


SIDE_SIGN = {"right": 1.0, "left": -1.0}    # which side of the object along the across axis each hand takes
PALM_ROLL_DEG = 90.0          # palm down rolled about the fingers: the right palm faces -x, thumb up
# The forearms come in side by side behind the object, closer than their own width: the right hand's
# fingers pitch down (a turn about its palm normal, so the palm stays flat on its face), lifting its
# wrist over the other's. Pitching both lifted both wrists to the same height, where they met.
FINGERS_DOWN_DEG = {"right": 30.0, "left": 0.0}
TOE_IN_DEG = 10.0             # fingers turned in towards the object, as a person's: the forearms swing out
SPREAD_M = 0.015              # each palm this far off its face while coming down and after letting go
SQUEEZE_M = 0.012            # each palm aimed this far inside its face: the arms' servos press it in
# The knuckle row this far short of the far face: set further forward, the wrist behind the palm meets
# the near face of an object deeper than the palm is long.
KNUCKLE_SHORT_M = 0.02
# How far the fingers close (0 open .. 1 the power grasp): fingers closed past a far edge pushed the
# cleaner back out between the palms (xarm7_leap, seeds 0-1: dropped; open: lifted), so the palms hold it.
FINGER_CLOSURE = 0.0
SQUEEZE_STEPS = 40
CARRY_STEPS = 200             # slow: a faster carry swung the object about the palms' axis
CARRY_CLEARANCE_M = 0.06      # its bottom above the target's top while carried: it sags in the palms
HOME_APART_M = 0.1            # return_home: each hand this much further out before it turns for home


def knuckle_reach(hand: HandDescription) -> float:
    """How far along the fingers the finger roots (the links on the palm) reach from the wrist site,
    the farthest of them: the knuckle row, past which the fingers bend."""
    palm = hand.links[0].name
    roots = np.array([link.origin.pos for link in hand.links if link.parent == palm])
    return float(hand.wrist_site.to_local(roots)[:, 2].max())


def across_axis(body_rot: np.ndarray, half_extents) -> tuple[np.ndarray, float, float]:
    """The object's horizontal axis nearest the world x axis (the line between the two arms), signed
    towards +x (the right hand's side), its half width along it, and the half depth along the other."""
    half = np.asarray(half_extents, float)
    axes = [body_rot[:, i] * np.array([1.0, 1.0, 0.0]) for i in (0, 1)]
    i = int(np.argmax([abs(a[0]) / max(np.linalg.norm(a), 1e-9) for a in axes]))
    a = axes[i] / np.linalg.norm(axes[i])
    across = float(np.abs(body_rot.T @ a) @ half)
    depth_dir = np.array([-a[1], a[0], 0.0])
    depth = float(np.abs(body_rot.T @ depth_dir) @ half)
    return (a if a[0] >= 0 else -a), across, depth


def hand_rotation(side: str, a: np.ndarray) -> np.ndarray:
    """Palm facing the object along the across axis ``a`` (the right palm -a, the left +a), fingers
    pointing away from the body (pitched down FINGERS_DOWN_DEG, turned in TOE_IN_DEG), thumb up."""
    rolled = axis_rotation(FORWARD, np.radians(PALM_ROLL_DEG * SIDE_SIGN[side])) @ PALM_DOWN
    pitched = axis_rotation(np.array([1.0, 0.0, 0.0]), -np.radians(FINGERS_DOWN_DEG[side])) @ rolled
    return yawed(pitched, float(np.arctan2(a[1], a[0])) + SIDE_SIGN[side] * np.radians(TOE_IN_DEG))


def plan(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
    name = item["carry"]
    task = op.scene.task
    obj = task.objects[name]
    centre = op.object_pos(data, name)
    body_rot = data.xmat[op.scene.object_body_ids[name]].reshape(3, 3).copy()
    a, across, depth = across_axis(body_rot, obj.half_extents)
    f = np.array([-a[1], a[0], 0.0])          # the fingers' heading: away from the body
    knuckles = knuckle_reach(load_embodiment(op.scene.layout.embodiment).hand)
    place = place_centre(op, data, item, name)          # the object's centre where it is let go
    op.leaves(name, rest_centre(place), on=item["place"])
    target_top = op.object_pos(data, item["place"])[2] + task.objects[item["place"]].half_extents[2]
    carry_z = target_top + CARRY_CLEARANCE_M + obj.half_extents[2]   # its bottom clears the target's top
    for side_name in ("right", "left"):
        side = op.sides[side_name]
        tl: SideTimeline = side["timeline"]
        out = SIDE_SIGN[side_name] * a
        # the palm's centre on the across face, the knuckles just short of the far face
        pitch = np.radians(FINGERS_DOWN_DEG[side_name])
        contact = (centre + float(item.get("grasp_height", 0.0)) * UP
                   + (depth - KNUCKLE_SHORT_M - knuckles * np.cos(pitch)) * f)
        hand_quat = quat(hand_rotation(side_name, a))
        squeezed = contact + out * (across - SQUEEZE_M)
        apart = contact + out * (across + SPREAD_M)
        held = squeezed - centre                       # the wrist from the object's centre, as held
        lifted = squeezed + max(LIFT_HEIGHT_M, carry_z - centre[2]) * UP
        reach = len(tl.frames)
        tl.add(DURATIONS["approach"], pos=apart + APPROACH_HEIGHT_M * UP, quat=hand_quat, hand=side["open"])
        tl.add(DURATIONS["descend"], pos=apart)
        tl.add(SQUEEZE_STEPS, pos=squeezed)
        tl.add(DURATIONS["close"], hand=op.power(side, (FINGER_CLOSURE, FINGER_CLOSURE)))   # the squeeze settles
        tl.add(DURATIONS["hold"])
        tl.add(DURATIONS["lift"], pos=lifted)
        op.look_again(side, name, data, reach, len(tl.frames))
        carry = len(tl.frames)
        over = place + held
        tl.add(CARRY_STEPS, pos=np.array([*over[:2], lifted[2]]))
        tl.add(DURATIONS["lower"], pos=over)
        tl.add(DURATIONS["open"], hand=side["open"])
        tl.add(SQUEEZE_STEPS, pos=over + out * (SQUEEZE_M + SPREAD_M))
        tl.add(DURATIONS["retreat"], pos=over + out * (SQUEEZE_M + SPREAD_M) + APPROACH_HEIGHT_M * UP)
        op.look_again(side, item["place"], data, carry, len(tl.frames))
        if item.get("return_home", False):
            # a person lowers their arms after setting a heavy thing down: the next step sets off from
            # home rather than from wherever the carry left the arm (the xArm7 holding the cleaner
            # ended on a branch from which the soap's pinch was 4 cm out of reach). The hands part
            # first: turning palm down beside the object, the fingers swept its top and tipped it.
            tl.add(DURATIONS["retreat"], pos=tl.frames[-1].pos + out * HOME_APART_M)
            tl.add(DURATIONS["approach"], pos=side["home"][0], quat=side["home"][1], hand=side["open"])
        # no slip correction before lowering (pick makes one): each palm rests about SQUEEZE_M outside
        # the target it is aimed at, so a correction would read that as slip and open the squeeze
