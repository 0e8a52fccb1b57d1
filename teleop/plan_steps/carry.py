"""Plan step `carry`: both hands carry an object too heavy for one (`hand: both`).

The way a person carries a heavy jug with both hands: the palms come down on opposite sides of it,
facing each other (thumbs up, fingers pointing away from the body, turned in a little), across the
object's horizontal axis nearest the line between the two arms (each hand stays on its own side),
at `grasp_height` above its centre (above its centre of mass it hangs between them rather than
tipping out). The palms press in (the squeeze holds the weight by friction), both lift it clear of
the target, carry it over, lower it to `place_offset` (as `pick`'s), let go, move apart and rise;
with `return_home`, both then go back to their home poses. With `place_from: front` (a container open
at a side, a microwave) they carry it level to outside the opening (teleop/plan_steps/front_place.py
finds it), slide it in, set it on the cavity floor, part until the hands are clear of it and draw
back out the way they came.
Both hands' timelines start together (teleop/scripted_operator.py waits for both to be free) and
their keyframes share the same steps, so the object is never pulled apart; with `approach_over` each
hand comes to the object over anything in its way (teleop/transit.py), and the one there first waits.
"""

from __future__ import annotations


import mujoco
import numpy as np

from sim.demo_plan import PLACE_FROM_FRONT
from sim.embodiment.description import HandDescription, load_embodiment
from sim.scene.reach import PALM_DOWN
from teleop.flat_pinch import width_along
from teleop.operator_motion import (APPROACH_HEIGHT_M, DURATIONS, FORWARD, LIFT_HEIGHT_M, UP, SideTimeline,
                                    axis_rotation, quat, yawed)
from teleop.plan_steps.front_place import (CEILING_GAP_M, SLIDE_STEPS as FRONT_SLIDE_STEPS, SideOpening,
                                           front_release, side_opening, slide_clearance, slide_start)
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.pick_place import place_centre, rest_centre
from teleop.transit import bounding_box_points, hand_outline


SIDE_SIGN = {"right": 1.0, "left": -1.0}    # which side of the object along the across axis each hand takes
PALM_ROLL_DEG = 90.0          # palm down rolled about the fingers: the right palm faces -x, thumb up
# The forearms come in side by side behind the object, closer than their own width: the right hand's
# fingers pitch down (a turn about its palm normal, so the palm stays flat on its face), lifting its
# wrist over the other's. Pitching both lifted both wrists to the same height, where they met.
FINGERS_DOWN_DEG = {"right": 30.0, "left": 0.0}
PITCH_STEP_DEG = 5.0          # ... less in steps of this, where the fingertips would reach below the object's bottom
TOE_IN_DEG = 10.0             # fingers turned in towards the object, as a person's: the forearms swing out (toe_in_deg)
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
RIM_CLEAR_M = 0.01            # front place: what of the open hand is over the object rises this far above its top
AT_HOME_M = 0.01              # a hand this close to its home position is there
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


def across_opening(model: mujoco.MjModel, data: mujoco.MjData, body: int,
                   out: np.ndarray) -> tuple[np.ndarray, float, float]:
    """As ``across_axis``, for an object slid in through a side opening facing ``out``: the palms go
    either side of it across the opening itself (signed towards +x), whatever its own yaw, the fingers
    pointing in (a bowl turned 16 degrees from the microwave, held along its own axes, was carried in
    askew and the hands met the cavity's walls); half width and depth are measured along those lines."""
    a = np.cross(UP, out)
    a = (a if a[0] >= 0 else -a) / np.linalg.norm(a)
    return a, width_along(model, data, body, a) / 2, width_along(model, data, body, out) / 2


def hand_rotation(side: str, a: np.ndarray, pitch_deg: float | None = None,
                  toe_in_deg: float = TOE_IN_DEG) -> np.ndarray:
    """Palm facing the object along the across axis ``a`` (the right palm -a, the left +a), fingers
    pointing away from the body (pitched down ``pitch_deg``, default FINGERS_DOWN_DEG, turned in
    ``toe_in_deg``), thumb up."""
    pitch = FINGERS_DOWN_DEG[side] if pitch_deg is None else pitch_deg
    rolled = axis_rotation(FORWARD, np.radians(PALM_ROLL_DEG * SIDE_SIGN[side])) @ PALM_DOWN
    pitched = axis_rotation(np.array([1.0, 0.0, 0.0]), -np.radians(pitch)) @ rolled
    return yawed(pitched, float(np.arctan2(a[1], a[0])) + SIDE_SIGN[side] * np.radians(toe_in_deg))


def fingers_pitch(op: PlanningOperator, side: str, a: np.ndarray, above_bottom: float,
                  toe_in_deg: float = TOE_IN_DEG) -> float:
    """FINGERS_DOWN_DEG for ``side``, less (in PITCH_STEP_DEG steps, down to level) while the open hand's
    lowest point would be below the object's bottom, ``above_bottom`` under the wrist site: the
    fingertips of a hand pressing on a low object (a bowl) would meet what it stands on, the table or
    the floor of the cavity it is slid into (microwave_bowl_loading: they caught the microwave's floor)."""
    s = op.sides[side]
    outline = hand_outline(s["hand"], side, s["open"])
    for pitch in np.arange(FINGERS_DOWN_DEG[side], 0.0, -PITCH_STEP_DEG):
        if float((outline @ hand_rotation(side, a, pitch, toe_in_deg).T)[:, 2].min()) >= -above_bottom:
            return float(pitch)
    return 0.0


def plan(op: PlanningOperator, data: mujoco.MjData, item: dict) -> None:
    name = item["carry"]
    task = op.scene.task
    obj = task.objects[name]
    centre = op.object_pos(data, name)
    body_rot = data.xmat[op.scene.object_body_ids[name]].reshape(3, 3).copy()
    knuckles = knuckle_reach(load_embodiment(op.scene.layout.embodiment).hand)
    front = item.get("place_from") == PLACE_FROM_FRONT
    if front:       # slid in level through the container's side opening, let go on its floor
        between = (op.sides["right"]["home"][0] + op.sides["left"]["home"][0]) / 2    # where the hands rest
        place = front_release(op, data, item, name)
        way_in = side_opening(op, data, item["place"], between, rays_at=float(place[2]))   # at the compartment's height
        a, across, depth = across_opening(op.scene.model, data, op.scene.object_body_ids[name], way_in.out)
        f = -way_in.out                       # the fingers point in through the opening
        carry_z = -np.inf
    else:
        a, across, depth = across_axis(body_rot, obj.half_extents)
        f = np.array([-a[1], a[0], 0.0])          # the fingers' heading: away from the body
        place = place_centre(op, data, item, name)          # the object's centre where it is let go
        target_top = op.object_pos(data, item["place"])[2] + task.objects[item["place"]].half_extents[2]
        carry_z = target_top + CARRY_CLEARANCE_M + obj.half_extents[2]   # its bottom clears the target's top
    op.leaves(name, rest_centre(place), on=item["place"])
    holds = {}
    box = bounding_box_points(op.scene.model, data, op.scene.object_body_ids[name])[:, 2]
    bottom, top = float(centre[2] - box.min()), float(box.max() - centre[2])
    height = float(item.get("grasp_height", 0.0))
    toe_in = TOE_IN_DEG if item.get("toe_in_deg") is None else float(item["toe_in_deg"])
    for side_name in ("right", "left"):
        out = SIDE_SIGN[side_name] * a
        # the palm's centre on the across face, the knuckles just short of the far face
        pitch_deg = fingers_pitch(op, side_name, a, height + bottom, toe_in)
        pitch = np.radians(pitch_deg)
        contact = centre + height * UP + (depth - KNUCKLE_SHORT_M - knuckles * np.cos(pitch)) * f
        holds[side_name] = (out, hand_rotation(side_name, a, pitch_deg, toe_in), contact + out * (across - SQUEEZE_M),
                            contact + out * (across + SPREAD_M))
    if front:
        back, slide = front_path(op, data, name, holds, centre, place, way_in, slide_clearance(item))
    # both set off from their home poses, as when the carry comes first: a hand an earlier step left
    # elsewhere (the right hand over the bowl it has just laid the baguette in) goes home first, the
    # other holding still
    if any(np.linalg.norm(op.sides[s]["timeline"].frames[-1].pos - op.sides[s]["home"][0]) > AT_HOME_M
           for s in holds):
        for side_name in holds:
            side = op.sides[side_name]
            side["timeline"].add(DURATIONS["approach"], pos=side["home"][0], quat=side["home"][1], hand=side["open"])
    reach = {s: len(op.sides[s]["timeline"].frames) for s in holds}
    for side_name in ("right", "left"):
        side = op.sides[side_name]
        _, hand_rot, _, apart = holds[side_name]
        over = dict(pos=apart + APPROACH_HEIGHT_M * UP, quat=quat(hand_rot), hand=side["open"])
        if item.get("approach_over", False):    # over anything in the way, the place too (transit.py)
            op.set_off(side, data, {"carry": name}, DURATIONS["approach"], **over)
        else:
            side["timeline"].add(DURATIONS["approach"], **over)
    # a hand that rose over something waits for the other there: they squeeze together
    ready_at = max(op.sides[s]["timeline"].end for s in holds)
    for side_name in holds:
        tl = op.sides[side_name]["timeline"]
        if tl.end < ready_at:
            tl.add(ready_at - tl.end)
    for side_name in ("right", "left"):
        side = op.sides[side_name]
        tl: SideTimeline = side["timeline"]
        out, hand_rot, squeezed, apart = holds[side_name]
        held = squeezed - centre                       # the wrist from the object's centre, as held
        lifted = squeezed + max(LIFT_HEIGHT_M, carry_z - centre[2]) * UP
        tl.add(DURATIONS["descend"], pos=apart)
        tl.add(SQUEEZE_STEPS, pos=squeezed)
        tl.add(DURATIONS["close"], hand=op.power(side, (FINGER_CLOSURE, FINGER_CLOSURE)))   # the squeeze settles
        tl.add(DURATIONS["hold"])
        tl.add(DURATIONS["lift"], pos=lifted)
        op.look_again(side, name, data, reach[side_name], len(tl.frames))
        carry = len(tl.frames)
        if front:       # to outside the opening, in along it, down onto the floor; the palms part and draw back out
            slide_in_and_part(op, side_name, holds[side_name], held, place, slide, back, way_in,
                              (across, depth, top), f)
        else:
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


def front_path(op: PlanningOperator, data: mujoco.MjData, name: str, holds: dict, centre: np.ndarray,
               place: np.ndarray, way_in: SideOpening, clearance: float) -> tuple[float, np.ndarray]:
    """`place_from: front`: how far out along the opening (from where the object's centre is let go at
    ``place``) the object and both hands holding it are clear of the opening's plane, and the object
    centre's height-adjusted ``place`` it slides in at (its bottom ``clearance`` above the cavity floor)."""
    model = op.scene.model
    ahead = [bounding_box_points(model, data, op.scene.object_body_ids[name]) - centre]
    for side_name, (_, hand_rot, squeezed, _) in holds.items():
        side = op.sides[side_name]
        closed = op.power(side, (FINGER_CLOSURE, FINGER_CLOSURE))
        ahead.append(hand_outline(side["hand"], side_name, closed, side["open"]) @ hand_rot.T + (squeezed - centre))
    return slide_start(place, way_in, float(np.max(np.concatenate(ahead) @ -way_in.out)), clearance)


def slide_in_and_part(op: PlanningOperator, side_name: str, hold: tuple, held: np.ndarray, place: np.ndarray,
                      slide: np.ndarray, back: float, way_in: SideOpening, extent: tuple[float, float, float],
                      f: np.ndarray) -> None:
    """`place_from: front`, one hand's frames from the lift on: carried to ``back`` outside the opening at
    the ``slide`` height, slid in, lowered to let go at ``place`` (the object's centre; the wrist is
    ``held`` from it), eased off and risen clear, parted and drawn back out. ``extent``: the object's
    half width across, half depth along the fingers ``f`` and its top above its centre."""
    side = op.sides[side_name]
    tl: SideTimeline = side["timeline"]
    out, hand_rot, _, _ = hold
    across, depth, top = extent
    over = place + held
    tl.add(CARRY_STEPS, pos=slide + back * way_in.out + held)
    tl.add(FRONT_SLIDE_STEPS, pos=slide + held)
    tl.add(DURATIONS["lower"], pos=over)
    tl.add(DURATIONS["open"], hand=side["open"])
    # the palm eases off the object's side, then whatever of the hand reaches over the object
    # (a thumb's base over a bowl's rim) rises clear of its top: parted straight away, the
    # thumbs dragged the rim and tipped the baguette out (microwave_bowl_loading, stream path)
    open_pts = hand_outline(side["hand"], side_name, side["open"]) @ hand_rot.T + held    # from the object's centre
    hand_pts = open_pts + out * SQUEEZE_M
    above = hand_pts[(hand_pts @ out < across - RIM_CLEAR_M) & (np.abs(hand_pts @ f) <= depth)]
    rise = 0.0 if not len(above) else max(0.0, top + RIM_CLEAR_M - float(above[:, 2].min()))
    rise = min(rise, max(0.0, way_in.ceiling - CEILING_GAP_M - float(place[2] + hand_pts[:, 2].max())))
    tl.add(SQUEEZE_STEPS, pos=over + out * SQUEEZE_M)
    tl.add(DURATIONS["retreat"], pos=over + out * SQUEEZE_M + rise * UP)
    # drawn straight back out, the fingertips (turned in) pass behind the object's far side: the palms
    # part until the whole hand is clear of it (microwave_bowl_loading: parted SPREAD_M off the bowl,
    # the tips hooked it back out onto the table)
    inner = float(np.min(open_pts @ out))
    part = max(SQUEEZE_M + SPREAD_M, across + SPREAD_M - inner)
    tl.add(SQUEEZE_STEPS, pos=over + out * part + rise * UP)
    tl.add(FRONT_SLIDE_STEPS, pos=over + out * part + rise * UP + back * way_in.out)
