"""A pinch for thin, flat objects (a wrench, a jigsaw piece, a spatula lying on a table).

A person picks a key off a table with the tips of the thumb and the index finger: the fingers point
down, the tips touch the table on either side of the key and close along it, the wrist sinking as
the fingers curl so the tips stay on the table. The pad pinch (teleop/pinch_grasp.py) cannot do
that: its pads meet 2-4 cm above the ends of the fingers, which reach the table first.

For any hand, the same grasp comes out of its description, as the pad pinch does: the pinching
fingers' "tips" are the points of their distal links' geoms furthest out past the pad points; the
thumb's tip is brought onto them by a bounded Levenberg-Marquardt solve (the other fingers folded
away); the hand is turned (pitch, then roll about the fingers) so that, spread to the object's
width, every tip is down at the bottom of the hand, the arm's flange kept off the table. No
per-hand numbers. The plan step (teleop/plan_steps/pick_place.py, `grasp: flat_pinch`) brings the
hand down and closes it.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import mujoco
import numpy as np

from sim.embodiment.mirror import M
from sim.scene.reach import PALM_DOWN
from teleop.operator_motion import FORWARD, axis_rotation, pitched_palm_down
from teleop.pinch_grasp import (DAMPING, MEET_M, SOLVE_ITERS, damped_step, hand_kinematics, moving_and_folded,
                                pinch_grasp, pinch_rows)
from teleop.transit import hand_outline, object_geoms

FD_STEP = 1e-5                 # rad: finite-difference step of the tips' Jacobian
PITCHES_DEG = np.arange(-30.0, 91.0, 5.0)     # fingers from 30 degrees up to straight down
ROLLS_DEG = np.arange(-60.0, 61.0, 5.0)        # turned about the fingers
BASE_CLEARANCE_M = 0.08     # the arm's flange (the hand's base) kept this high over the tips: off the table
# grasp_arm_clear: other turns whose highest tip is at most this much higher than the best's (the RH5DG2's [index,
# middle] pinch: rolls -15, -20, -30, -35 degrees within 0.6 mm; within 1 mm none kept the UR5's left arm off the pen
# cup taking the pen on seed 3)
NEAR_ROTATION_M = 0.003


@dataclass(frozen=True)
class TipPinch:
    close: np.ndarray           # actuator targets (hand order): the thumb's tip on the fingers' tips
    gap_m: float                # largest remaining distance between the thumb's tip and a finger's
    fingers: tuple[str, ...]    # the fingers the thumb pinches against (the pad pinch's)
    moving: np.ndarray          # (hand order) the actuators of the thumb and those fingers; the rest stay folded


def _tips(hand_name: str, fingers: tuple[str, ...]) -> list[tuple[int, np.ndarray]]:
    """(body id in the hand model, point in the body frame) of the thumb's tip and ``fingers``' tips:
    the point of the distal link's geoms furthest along the direction of its retarget pad point."""
    kin = hand_kinematics(hand_name)
    by_finger = {t.finger: t.point for t in kin.spec.fingertips}
    links = {link.name: link for link in kin.hand.links}
    out = []
    for finger in ("thumb", *fingers):
        point = by_finger[finger]
        u = np.asarray(point.pos, float)
        u = u / np.linalg.norm(u)
        support = max((g.support(u) for g in links[point.body].geoms), key=lambda p: p @ u)
        out.append((kin.model.body(point.body).id, support))
    return out


def tip_points(hand_name: str, fingers: tuple[str, ...], q: np.ndarray) -> np.ndarray:
    """(1 + fingers, 3) the thumb's tip then ``fingers``' tips at actuator targets ``q``, in the
    wrist-site frame (right hand)."""
    kin = hand_kinematics(hand_name)
    kin.points(np.asarray(q, float))            # sets the configuration
    d = kin.data
    world = [d.xpos[b] + d.xmat[b].reshape(3, 3) @ p for b, p in _tips(hand_name, fingers)]
    return kin.hand.wrist_site.to_local(np.array(world))


@functools.lru_cache(maxsize=None)
def tip_pinch(hand_name: str, fingers: tuple[str, ...] | None = None) -> TipPinch:
    """The thumb's tip brought onto the pad pinch's fingers' tips, from the pad pinch's closed shape
    (the nearest natural start), the other fingers folded away as there. ``fingers`` (a plan step's
    `pinch_fingers`): the pad pinch with that set (default the hand's own, teleop/pinch_grasp.py)."""
    kin = hand_kinematics(hand_name)
    pads = pinch_grasp(hand_name, fingers)
    fingers = pads.fingers
    thumb, tips = pinch_rows(hand_name, fingers)
    moving, folded = moving_and_folded(kin, [thumb, *tips])

    def residual(q):
        P = tip_points(hand_name, fingers, q)
        return np.concatenate([P[0] - P[k] for k in range(1, len(P))])

    def gap(q):
        return float(np.max(np.linalg.norm(residual(q).reshape(-1, 3), axis=1)))

    q = np.where(moving, pads.close, folded)
    q_gap, damping = gap(q), DAMPING
    cols = np.flatnonzero(moving)
    for _ in range(SOLVE_ITERS):
        r = residual(q)
        A = np.empty((len(r), len(cols)))
        for j, c in enumerate(cols):
            dq = q.copy()
            dq[c] += FD_STEP
            A[:, j] = (residual(dq) - r) / FD_STEP
        q, q_gap, damping = damped_step(kin, q, cols, A, r, damping, gap, q_gap)
        if q_gap <= 0.2 * MEET_M:
            break
    q.flags.writeable = moving.flags.writeable = False       # cached: shared by every caller
    return TipPinch(close=q, gap_m=q_gap, fingers=fingers, moving=moving)


def refolded(hand_name: str, close: np.ndarray, fold: float, fingers: tuple[str, ...] | None = None) -> np.ndarray:
    """``close`` with the fingers that do not pinch folded ``fold`` of the way to their closed end (a plan
    step's `pinch_fold`) rather than tip_pinch's FOLD_FRACTION: folded that far, the DexHand021's pressed a
    jigsaw piece's top beside the tips and turned it over in the hand."""
    pinch = tip_pinch(hand_name, fingers)
    thumb, tips = pinch_rows(hand_name, pinch.fingers)
    _, folded = moving_and_folded(hand_kinematics(hand_name), [thumb, *tips], fold)
    return np.where(pinch.moving, close, folded)


def tip_preshape(hand_name: str, open_: np.ndarray, close: np.ndarray, width_m: float,
                 fingers: tuple[str, ...] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """As ``pinch_preshape`` for the tips: the actuator targets on the way from ``open_`` to
    ``close`` as closed as possible with the thumb's tip ``width_m`` from every finger's, and the
    point midway between the thumb's tip and the fingers' there (wrist-site frame, right hand)."""
    fingers = tip_pinch(hand_name, fingers).fingers
    for s in np.linspace(1.0, 0.0, 21):
        q = open_ + s * (close - open_)
        P = tip_points(hand_name, fingers, q)
        if min(np.linalg.norm(P[0] - P[k]) for k in range(1, len(P))) >= width_m:
            break
    return q, 0.5 * (P[0] + P[1:].mean(axis=0))


def tip_axis(hand_name: str, q: np.ndarray, fingers: tuple[str, ...] | None = None) -> np.ndarray:
    """Unit vector from the thumb's tip to the fingers' tips at ``q`` (wrist-site frame, right hand)."""
    P = tip_points(hand_name, tip_pinch(hand_name, fingers).fingers, q)
    axis = P[1:].mean(axis=0) - P[0]
    return axis / np.linalg.norm(axis)


def tips_over_lowest(hand_name: str, side: str, q: np.ndarray, R: np.ndarray, outline_q: np.ndarray | None = None,
                     fingers: tuple[str, ...] | None = None) -> float:
    """How high the thumb's and the pinching fingers' lowest tip at actuator targets ``q`` is over the hand's
    lowest point at ``outline_q`` (default ``q``), the hand turned ``R`` (world from wrist site)."""
    tips = tip_points(hand_name, tip_pinch(hand_name, fingers).fingers, q)
    tips = tips @ M if side == "left" else tips
    lowest = hand_outline(hand_name, side, q if outline_q is None else outline_q)
    return float((tips @ R.T)[:, 2].min() - (lowest @ R.T)[:, 2].min())


def _turned(pitch_deg: float, roll_deg: float) -> np.ndarray:
    R = pitched_palm_down(pitch_deg)
    fingers = R @ (PALM_DOWN.T @ FORWARD)
    return axis_rotation(fingers, np.radians(roll_deg)) @ R


def flat_pinch_rotation(hand_name: str, side: str, ready: np.ndarray, fingers: tuple[str, ...] | None = None) -> np.ndarray:
    """The hand's rotation (world from wrist site, before any yaw) for a flat pinch: of the pitches
    and the rolls about the fingers, the one that brings every tip of the spread hand (``ready``)
    nearest to the bottom of the hand."""
    return _flat_pinch_rotation(hand_name, side, tuple(np.round(ready, 6)), fingers)


@functools.lru_cache(maxsize=None)
def _scored_rotations(hand_name: str, side: str, ready: tuple, fingers: tuple[str, ...] | None
                      ) -> tuple[tuple[float, np.ndarray], ...]:
    """(cost, rotation) of every pitch and roll about the fingers, in the order tried: the cost is how high the
    spread hand's (``ready``) highest tip sits above the bottom of the hand, plus how far the arm's flange comes
    below BASE_CLEARANCE_M over it."""
    q = np.array(ready)
    tips = tip_points(hand_name, tip_pinch(hand_name, fingers).fingers, q)
    tips = tips @ M if side == "left" else tips
    outline = hand_outline(hand_name, side, q)
    base = hand_kinematics(hand_name).hand.wrist_site.to_local(np.zeros(3))
    base = base @ M if side == "left" else base
    scored = []
    for pitch in PITCHES_DEG:
        for roll in ROLLS_DEG:
            R = _turned(pitch, roll)
            R.flags.writeable = False
            low = (outline @ R.T)[:, 2].min()
            cost = (tips @ R.T)[:, 2].max() - low     # the highest tip above the bottom of the hand
            cost += max(0.0, BASE_CLEARANCE_M - ((R @ base)[2] - low))    # the arm kept off the table
            scored.append((cost, R))
    return tuple(scored)


@functools.lru_cache(maxsize=None)
def _flat_pinch_rotation(hand_name: str, side: str, ready: tuple, fingers: tuple[str, ...] | None) -> np.ndarray:
    best, best_cost = None, np.inf
    for cost, R in _scored_rotations(hand_name, side, ready, fingers):
        if cost < best_cost - 1e-9:
            best, best_cost = R, cost
    return best


@functools.lru_cache(maxsize=None)
def near_rotations(hand_name: str, side: str, ready: tuple, fingers: tuple[str, ...] | None) -> tuple[np.ndarray, ...]:
    """flat_pinch_rotation's rotation first, then the other pitches and rolls whose highest tip is within
    NEAR_ROTATION_M of its, nearest first: a flat pinch as good, with the arm turned another way (`grasp_arm_clear`)."""
    best = _flat_pinch_rotation(hand_name, side, ready, fingers)
    scored = _scored_rotations(hand_name, side, ready, fingers)
    least = min(cost for cost, _ in scored)
    near = sorted(((c, R) for c, R in scored if c <= least + NEAR_ROTATION_M and not np.allclose(R, best)),
                  key=lambda cR: cR[0])
    return (best, *(R for _, R in near))


def width_along(model: mujoco.MjModel, data: mujoco.MjData, body: int, axis: np.ndarray,
                through: np.ndarray | None = None) -> float:
    """How wide object ``body`` is along the horizontal line through its centre (or the world point
    ``through``) in direction ``axis`` (world): the span of that line inside its geoms' bounding boxes
    (a wrench's handle, not its head)."""
    centre = data.xpos[body] if through is None else np.asarray(through, float)
    u = np.array([axis[0], axis[1], 0.0]) / np.linalg.norm(axis[:2])
    lo, hi = np.inf, -np.inf
    for g in object_geoms(model, body):
        R = data.geom_xmat[g].reshape(3, 3)
        c = data.geom_xpos[g] + R @ model.geom_aabb[g, :3]
        half = model.geom_aabb[g, 3:]
        p, d = (centre - c) @ R, u @ R            # the line in the box's frame
        t0, t1 = -np.inf, np.inf
        for k in range(3):
            if abs(d[k]) < 1e-12:
                if abs(p[k]) > half[k]:
                    t0, t1 = np.inf, -np.inf
                continue
            a, b = sorted(((-half[k] - p[k]) / d[k], (half[k] - p[k]) / d[k]))
            t0, t1 = max(t0, a), min(t1, b)
        if t0 <= t1:
            lo, hi = min(lo, t0), max(hi, t1)
    return float(hi - lo) if hi >= lo else 0.0
