"""`place_from: front` on a `pick`: set the held object into a container open at a side (a
microwave, a fridge shelf, a cabinet) the way a person does, not lowered from above.

The object is carried level to just outside the opening, its bottom clear of the cavity floor; slid
in along the opening to its place; lowered onto the floor and let go; the open hand rises off it
(within the cavity), is drawn back out the way it came and goes back to where it rests (it would
stand in the way of a door shut next).
The opening is found by rays against the container's own walls: its links (a door, open or shut) are
not walls. The rays start at the cavity's centre raised or lowered to the height of what goes in or
comes out: a shelf across the cavity's middle (a fridge's) is not in their way there.
With `slide_fingers_in` (opt-in) the hand turns about the vertical on its way to the opening so that its
fingers point straight in, and the arm behind it comes through the mouth rather than across the container's side.
With `slide_as_held` (opt-in) the look outside the opening moves the slide for where the object sits in the hand
but leaves the hand's turn as planned: an object lying on its side (a banana) has no up to stand it by.
"""

from __future__ import annotations

from typing import NamedTuple

import mujoco
import numpy as np

from sim.embodiment.frames import quat_to_mat
from sim.errors import SpecError
from sim.scene.reach import PALM_DOWN
from teleop.geom_rays import body_geoms, nearest_hit
from teleop.operator_motion import DURATIONS, FORWARD, UP, SideTimeline, quat, yawed
from teleop.plan_steps.operator import PlanningOperator
from teleop.plan_steps.upright_look import upright_look
from teleop.transit import bounding_box_points, hand_outline

# the object's bottom above the cavity floor while it slides in: a bowl held by its rim hangs tilted
SLIDE_CLEARANCE_M = 0.04
OUTSIDE_M = 0.03           # before sliding in, the hand's and the object's leading points this far outside the opening
RELEASE_GAP_M = 0.005      # let go this far above the floor (as pick_place)
WITHDRAW_RISE_M = 0.015    # the open hand rises at least this much off the object before it draws back
OFF_TOP_M = 0.01           # ... and until its lowest point is this far above the object's top
CEILING_GAP_M = 0.01       # ... its highest point staying this far under the cavity's ceiling
RAY_FREE_M = 10.0          # a ray from the cavity's centre running this far without a wall leaves by the opening
# carried to the opening and slid in slowly: a bowl held by its rim swings about the pads when a faster
# move starts and stops (microwave_bowl_loading, 60 steps each: it slid off the pads or tipped at the opening)
CARRY_STEPS, SLIDE_STEPS = 180, 120


def opening(model: mujoco.MjModel, data: mujoco.MjData, body: int, centre: np.ndarray, towards: np.ndarray,
            source="demo_plan") -> np.ndarray:
    """The unit direction (world, horizontal) out of the container ``body``'s open side: of its frame's
    four horizontal axes, each way, those whose ray from the cavity ``centre`` meets none of the
    body's own geoms; of several, the one facing ``towards`` (where the hand rests)."""
    R = data.xmat[body].reshape(3, 3)
    free = []
    for axis in (0, 1):
        for sign in (-1.0, 1.0):
            d = sign * R[:, axis]
            hit = nearest_hit(model, data, body_geoms(model, body), centre, d)
            if hit is None or hit > RAY_FREE_M:
                free.append(d)
    if not free:
        raise SpecError(source, "demo_plan.place_from", "a container open at a side (front)", model.body(body).name)
    return max(free, key=lambda d: float(d @ (towards - centre)))


class SideOpening(NamedTuple):
    """A container's side opening (world): ``out`` the unit direction out of it (horizontal), ``mouth``
    a point of its plane, the cavity's ``centre``, ``floor`` and ``ceiling`` heights."""

    out: np.ndarray
    mouth: np.ndarray
    centre: np.ndarray
    floor: float
    ceiling: float


def _cavity(op: PlanningOperator, data: mujoco.MjData, container: str):
    """``container``'s body, rotation (world), cavity centre (world) and half extents (its frame)."""
    target = op.scene.task.objects[container]
    body = op.scene.object_body_ids[container]
    R = data.xmat[body].reshape(3, 3)
    return body, R, data.xpos[body] + R @ np.asarray(target.interior_offset, float), \
        np.asarray(target.interior_half_extents, float)


def cavity_floor(op: PlanningOperator, data: mujoco.MjData, container: str) -> float:
    """The world height of ``container``'s cavity floor."""
    _, R, centre, half = _cavity(op, data, container)
    return float(centre[2]) - float(np.abs(R[2]) @ half)


def side_opening(op: PlanningOperator, data: mujoco.MjData, container: str, towards: np.ndarray,
                 rays_at: float | None = None) -> SideOpening:
    """The side ``container`` is open at (of several, the one facing ``towards``) and its cavity; the
    rays that find it start at the cavity's centre, at world height ``rays_at`` if given (the compartment
    an object goes into or comes out of: from the cavity's middle they would start inside a shelf)."""
    body, R, centre, half = _cavity(op, data, container)
    rays_from = centre if rays_at is None else np.array([centre[0], centre[1], rays_at])
    out = opening(op.scene.model, data, body, rays_from, towards, op.scene.task.source)
    mouth = centre + float(np.abs(R.T @ out) @ half) * out
    height = float(np.abs(R[2]) @ half)
    return SideOpening(out, mouth, centre, float(centre[2]) - height, float(centre[2]) + height)


def front_release(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str) -> np.ndarray:
    """Where the centre of object ``name`` is let go in the step's `place`: `place_offset` [dx, dy] from
    the container's centre, the release gap above [dz above] the cavity floor."""
    dx, dy, dz = [*item.get("place_offset", [0.0, 0.0]), 0.0][:3]
    return np.array([*(op.object_pos(data, item["place"])[:2] + [dx, dy]),
                     cavity_floor(op, data, item["place"]) + dz + op.scene.task.objects[name].rest_height
                     + RELEASE_GAP_M])


def slide_clearance(item: dict) -> float:
    """A front place's `slide_clearance_m`: the object's bottom above the cavity floor as it slides in
    (default SLIDE_CLEARANCE_M)."""
    value = item.get("slide_clearance_m")
    return SLIDE_CLEARANCE_M if value is None else float(value)


def slide_start(place: np.ndarray, way_in: SideOpening, lead: float,
                clearance: float = SLIDE_CLEARANCE_M) -> tuple[float, np.ndarray]:
    """How far out along the opening, from ``place`` (where what is slid in is let go), it starts so
    that what reaches ``lead`` ahead of ``place`` into the opening is clear of the opening's plane; and
    ``place`` at the height it slides in at (its bottom ``clearance`` above the cavity floor)."""
    back = max(0.0, float((place - way_in.mouth) @ -way_in.out) + lead + OUTSIDE_M)
    return back, place + (clearance - RELEASE_GAP_M) * UP


FINGERS = PALM_DOWN.T @ FORWARD      # the way the fingers point, wrist-site frame


def fingers_in_turn(hand_rot: np.ndarray, out: np.ndarray) -> float:
    """The turn (radians, about the vertical) that points the hand's fingers (``hand_rot``), seen from
    above, straight in through an opening facing ``out``."""
    fingers = hand_rot @ FINGERS
    turn = np.arctan2(-out[1], -out[0]) - np.arctan2(fingers[1], fingers[0])
    return float((turn + np.pi) % (2 * np.pi) - np.pi)


def carry_and_place_front(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str,
                          offset: np.ndarray) -> None:
    """The held object ``name`` (its centre ``offset`` from the wrist, world) carried from where the hand
    is to in front of the step's `place`, slid in through its opening to `place_offset` [dx, dy] from its
    centre (dz: above the cavity floor), lowered, let go; the hand drawn back out and home."""
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    model = op.scene.model
    # the opening is looked for at the height the object is let go at: the compartment it goes into
    release = front_release(op, data, item, name)
    way_in = side_opening(op, data, item["place"], side["home"][0], rays_at=float(release[2]))
    out = way_in.out
    R_hand = quat_to_mat(tl.frames[-1].quat)
    turn, turned = np.eye(3), {}
    if item.get("slide_fingers_in"):
        # the hand turned about the vertical on the way so its fingers point straight in: the forearm behind
        # it comes through the mouth, not across the container's side wall or an open door's edge
        turn = yawed(np.eye(3), fingers_in_turn(R_hand, out))
        R_hand, offset = turn @ R_hand, turn @ offset
        turned = {"quat": quat(R_hand)}
    place = release - offset      # wrist, letting go
    op.leaves(name, place + offset - RELEASE_GAP_M * UP, on=item["place"])
    # how far ahead of the wrist (into the opening) the open or closed hand and the object reach
    body_pts = bounding_box_points(model, data, op.scene.object_body_ids[name]) - op.object_pos(data, name)
    body_pts = body_pts @ turn.T + offset
    hand_pts = hand_outline(side["hand"], item["hand"], tl.frames[-1].hand, side["open"]) @ R_hand.T
    lead = float(np.max(np.concatenate([body_pts, hand_pts]) @ -out))
    # let go, the open hand rises until its lowest point clears the object's top (the fingers hooked
    # round a bowl's rim drag it back out otherwise), as far as the cavity's ceiling lets it
    open_pts = hand_outline(side["hand"], item["hand"], side["open"]) @ R_hand.T
    room = way_in.ceiling - CEILING_GAP_M - float(place[2] + max(open_pts[:, 2].max(), hand_pts[:, 2].max()))
    rise = max(WITHDRAW_RISE_M, min(float(body_pts[:, 2].max() + OFF_TOP_M - open_pts[:, 2].min()), room))
    back, slide = slide_start(place, way_in, lead, slide_clearance(item))
    carry_frame = len(tl.frames)
    op.set_off(side, data, item, CARRY_STEPS, pos=slide + back * out, carried=(name, offset), **turned)
    # outside the opening the operator looks where the object sits in the hand and corrects the rest
    first = len(tl.frames)
    tl.add(SLIDE_STEPS, pos=slide)
    tl.add(DURATIONS["lower"], pos=place)
    tl.add(DURATIONS["open"], hand=side["open"])
    tl.add(DURATIONS["retreat"], pos=place + rise * UP)
    tl.add(DURATIONS["retreat"], pos=place + rise * UP + back * out)
    # ... and how it leans: it goes in upright (a bottle handed over hangs in the hand as the giver let it go);
    # `slide_as_held`: only where it sits (a banana rolled in the grip has no up, the turn pitched the hand)
    up = data.xmat[op.scene.object_body_ids[name]].reshape(3, 3).T @ UP     # its up as it stood
    op.on_frame_end(side, first - 1, upright_look(op, side, name, up, R_hand, offset.copy(),
                                                  range(first, len(tl.frames)), recentre_when_upright=True,
                                                  turn=not item.get("slide_as_held")))
    op.look_again(side, item["place"], data, carry_frame, len(tl.frames))
    tl.add(DURATIONS["approach"], pos=side["home"][0], quat=side["home"][1])


