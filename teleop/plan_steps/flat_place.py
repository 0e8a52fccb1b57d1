"""How a flat pinch (teleop/flat_pinch.py) sets a thin object down where it belongs.

The tips sweep a thin object along the table before they hold it, so it sits in the hand centimetres
from where the plan put it, turned, and higher than planned (the tips, pressed onto the table, hold it
near their ends). A person placing a jigsaw piece looks at it in the hand, turns the hand so that the
piece comes down square to the piece it goes against, sets it onto the table and lets go by easing
the fingers apart only as far as they came in, slides the thumb off its side and lifts the hand away:

- as the hand sets off with the object, the operator looks where it sits in the hand (position, height
  and turn) and moves the carry, lowering and release with it, turning the hand about the vertical so
  that the object comes down square to the target object (up to its footprint's symmetry: a quarter
  turn for a square, a half turn otherwise); for `place: table` it keeps its turn;
- above the target, as the hand starts down, it looks again (the object turns and sinks in the hand
  while carried: 14 degrees on jigsaw seeds 0-1) and lowers it onto the table, PRESS_M below its
  release gap, turned square again;
- the hand opens only to the pre-shape it came down with (opened fully, the folded fingers swing out
  across the table), moves EASE_M away from the thumb's side and then lifts: the thumb, left against
  the object's side, dragged it 4-6 cm as the hand rose (jigsaw seeds 2-3, stream path; 1-2 cm with
  the ease); the hand opens fully on its way to what comes next.
- opt-in (a pick's fields): `release_pinch_only: true` opens only the thumb and the pinching fingers, the
  folded ones staying as they held (eased to the pre-shape they came down on a jigsaw piece's edge and
  lifted it with the hand); `place_press_m` lowers the object that far below its release height instead of
  PRESS_M (a piece held tilted, one edge on a fingertip, lies flatter before the hand opens);
  `release_relax: f` opens the thumb and the pinching fingers from where they hold, f of the way to the
  open hand (read as the hand is about to open), instead of to the pre-shape (relaxed_release);
  `place_yaw` (degrees) picks, of the turns that set the object square, the one with the tips closing (thumb
  to fingers) nearest that direction rather than the smallest (turn_toward): a jigsaw piece set against the
  near side of the fixed one, turned the least, came down with the fingertips on the fixed piece, which held
  it 1.7 cm up as the hand opened (jigsaw's yellow piece, left hand: place_yaw 0 lays it flat);
  `ease_turned: true` turns the ease off the thumb's side with the hand as the looks turn it (turn_ease).

jigsaw_puzzle_assembly__iiwa7_sharpa, stream path, seeds 0-11, green and red pieces set 8 mm clear
of the white one: 10 and 8 of 12 within the task's tolerance once let go (tests/teleop/test_flat_place.py).
"""

from __future__ import annotations

import mujoco
import numpy as np

from sim.demo_plan import TABLE_TARGET
from sim.embodiment.frames import quat_to_mat
from sim.embodiment.mirror import mirror_vec
from teleop.flat_pinch import tip_axis, tip_pinch
from teleop.operator_motion import UP, SideTimeline, quat, yaw_of, yawed
from teleop.pinch_grasp import pinch_fingers
from teleop.plan_steps.operator import PlanningOperator

LIFTED_M = 0.02         # an object this far above where it lay has been picked up
SQUARE_TOL_M = 0.002    # a footprint whose sides differ by less than this is square: a quarter turn maps it onto itself
PRESS_M = -0.006        # let go with its centre this far from the release height (pick_place's 5 mm gap: on the table)
EASE_M = 0.02           # after opening, the hand moves this far away from the thumb's side ...
EASE_UP_M = 0.003       # ... and this far up
EASE_STEPS = 15


def footprint_period(half_extents) -> float:
    """The turn (radians) that maps an object lying flat onto itself: a half turn; a quarter turn if square."""
    hx, hy = float(half_extents[0]), float(half_extents[1])
    return np.pi / 2 if abs(hx - hy) < SQUARE_TOL_M else np.pi


def square_turn(obj_rot: np.ndarray, target_rot: np.ndarray, half_extents) -> float:
    """The smallest turn (radians, about the vertical) that sets an object lying flat (rotation
    ``obj_rot``) square to a target (``target_rot``): their sides parallel, up to the object's
    footprint symmetry (footprint_period)."""
    period = footprint_period(half_extents)
    turn = yaw_of(target_rot) - yaw_of(obj_rot)
    return float((turn + period / 2) % period - period / 2)


def turn_toward(turn: float, period: float, heading: float, place_yaw: float) -> float:
    """Of the turns that set an object square (``turn`` plus whole ``period``s, within a half turn either
    way), the one that brings the hand's ``heading`` (the yaw of its thumb-to-fingers axis, radians)
    nearest ``place_yaw``."""
    turns = [turn + k * period for k in range(-4, 5) if abs(turn + k * period) <= np.pi + 1e-9]
    return min(turns, key=lambda t: abs((heading + t - place_yaw + np.pi) % (2 * np.pi) - np.pi))


def relaxed_release(side: dict, frames: slice, folded: np.ndarray, fraction: float, fingers: tuple[str, ...] | None = None):
    """A look (on_frame_end) as the hand lets go: the thumb and the pinching fingers open from the joint
    positions they hold at, ``fraction`` of the way to the open hand, for the keyframes ``frames`` (open,
    ease off, retreat); the other fingers stay ``folded``. A person relaxes a grip rather than opening to a
    shape: the held tips sit centimetres from where the pre-shape puts them, and opening to it swept them
    across the piece."""
    pinching = tip_pinch(side["hand"], fingers).moving

    def relax(now: mujoco.MjData) -> None:
        held = np.asarray(now.actuator_length[side["hand_ids"]], float)
        hand = np.where(pinching, held + fraction * (side["open"] - held), folded)
        for frame in side["timeline"].frames[frames]:
            frame.hand = hand
    return relax


def flat_place(op: PlanningOperator, data: mujoco.MjData, item: dict, name: str, offset: np.ndarray,
               carry_frame: int, lower_frame: int, release_hand: np.ndarray) -> None:
    """For a pick with `grasp: flat_pinch` whose carry starts at frame ``carry_frame`` and which
    ``lower_and_release`` has just ended (lower at ``lower_frame``, open, retreat): the looks and
    the release above. ``offset`` is the object's centre from the wrist as planned; ``release_hand``
    the hand's pre-shape as it came down."""
    side = op.sides[item["hand"]]
    tl: SideTimeline = side["timeline"]
    opened = tl.frames[lower_frame + 1]
    opened.hand = np.asarray(release_hand, float)
    fingers = pinch_fingers(item)
    if item.get("release_pinch_only"):
        # the folded fingers stay as they held: eased to the pre-shape they came down onto a jigsaw piece's edge
        # and lifted it with the hand (green and red pieces within tolerance on 3 -> 9 of 12, stream path)
        opened.hand = np.where(tip_pinch(side["hand"], fingers).moving, opened.hand, tl.frames[lower_frame].hand)
    # slide the thumb off the object's side before lifting the hand away
    retreat = tl.frames.pop()
    axis_site = tip_axis(side["hand"], release_hand, fingers)        # thumb to fingers, wrist-site frame (right hand) ...
    axis_site = mirror_vec(axis_site) if item["hand"] == "left" else axis_site     # ... this hand's
    axis = quat_to_mat(opened.quat) @ axis_site
    away = -np.array([axis[0], axis[1], 0.0]) / np.linalg.norm(axis[:2])
    tl.add(EASE_STEPS, pos=opened.pos + EASE_M * away + EASE_UP_M * UP)
    tl.add(retreat.end_step - opened.end_step, pos=retreat.pos + EASE_M * away)
    end = len(tl.frames)
    # `ease_turned: true`: the ease off the thumb's side turns with the hand as the looks below turn it; without
    # it, it keeps the direction planned before them, and a hand turned a quarter (place_yaw) slid along the
    # piece's side and dragged it 2-3 cm (jigsaw's yellow piece: placed on 3 -> 5 of 12)
    ease = {"d": EASE_M * away} if item.get("ease_turned") else None

    def turn_ease(turn: float) -> None:
        if ease is None:
            return
        d = yawed(ease["d"], turn)
        for frame in tl.frames[end - 2:end]:       # ease off, retreat
            frame.pos = frame.pos + d - ease["d"]
        ease["d"] = d

    carried_at, _, _, frames = side["corrections"][-1]     # lower_and_release's check above the target
    correction = (carried_at, name, offset, slice(frames.start, end))
    side["corrections"][-1] = correction
    obj = op.scene.task.objects[name]
    body = op.scene.object_body_ids[name]
    start_z = float(op.object_pos(data, name)[2])
    # `place_press_m`: lowered that far below the release height instead (a piece held tilted, one edge on a
    # fingertip, pressed flatter before letting go; 0.02 with release_pinch_only: green and red 9 -> 10 of 12)
    press = PRESS_M if item.get("place_press_m") is None else -float(item["place_press_m"])
    held = {"offset": None}         # the object's centre from the wrist as the carry turned it

    def turn_to_square(now: mujoco.MjData) -> float:
        if item["place"] == TABLE_TARGET:
            return 0.0
        target = now.xmat[op.scene.object_body_ids[item["place"]]].reshape(3, 3)
        turn = square_turn(now.xmat[body].reshape(3, 3), target, obj.half_extents)
        if item.get("place_yaw") is None:
            return turn
        # `place_yaw`: of the square turns, the one that sets the tips closing along it (a piece set against
        # another's side: the tips on its free sides, not between the two, where they landed on the other piece)
        closing = quat_to_mat(tl.frames[lower_frame].quat) @ axis_site
        return turn_toward(turn, footprint_period(obj.half_extents), float(np.arctan2(closing[1], closing[0])),
                           np.radians(item["place_yaw"]))

    def set_off(now: mujoco.MjData) -> None:
        if op.object_pos(now, name)[2] < start_z + LIFTED_M:
            return      # not in the hand: nothing to carry
        actual = op.object_pos(now, name) - now.site_xpos[side["wrist_site_id"]]
        turn = turn_to_square(now)
        turned = yawed(actual, turn)
        for frame in tl.frames[carry_frame:end]:
            centre = frame.pos + offset                 # where the plan has the object's centre
            frame.pos = centre - turned
            frame.quat = quat(yawed(quat_to_mat(frame.quat), turn))
        held["offset"] = turned
        turn_ease(turn)
        for i, entry in enumerate(side["corrections"]):
            if entry is correction:
                side["corrections"][i] = (carried_at, name, turned, correction[3])

    def lowering(now: mujoco.MjData) -> None:
        if held["offset"] is None:
            return
        actual = op.object_pos(now, name) - now.site_xpos[side["wrist_site_id"]]
        if np.linalg.norm(actual - held["offset"]) > LIFTED_M:
            return      # slipped out or badly: the plan's heights are as good a guess
        turn = turn_to_square(now)
        # the check above the target (same step, just before) has moved these frames across for where
        # it sits: along them the object's centre is each frame's position plus where it sits now, at
        # the plan's height
        turned = yawed(actual, turn)
        for frame in tl.frames[lower_frame:end]:
            centre = frame.pos + np.array([actual[0], actual[1], held["offset"][2] + press])
            frame.pos = centre - turned
            frame.quat = quat(yawed(quat_to_mat(frame.quat), turn))
        turn_ease(turn)

    op.on_frame_end(side, carry_frame - 1, set_off)
    op.on_frame_end(side, lower_frame - 1, lowering)
    if item.get("release_relax") is not None:     # jigsaw green and red: 10 -> 12 of 12 within 7 mm (stream path)
        folded = tl.frames[lower_frame].hand
        op.on_frame_end(side, lower_frame, relaxed_release(side, slice(lower_frame + 1, end), folded,
                                                           float(item["release_relax"]), fingers))
