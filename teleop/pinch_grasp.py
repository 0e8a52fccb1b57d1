"""A precision (pinch) grasp for small objects, found from the hand's own kinematics.

A person picks a golf ball or a pill bottle off a table between the thumb and the first one or two
fingers, the other fingers folded out of the way. For any hand, the same grasp comes out of its
description: over the hand's actuated joints (couplings followed, as in simulation), the thumb pad
is brought onto the pinching fingers' pads (the `retarget:` block's fingertip points) by a bounded
Levenberg-Marquardt solve, the other fingers are folded towards their closed end, and the point where
the pads meet, expressed in the wrist-site frame, is where the object's centre goes.

Closing towards a configuration where the pads meet leaves the servos pressing the object between
them once they stop on it. No per-hand numbers: a new hand file gets a pinch for free.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Callable

import numpy as np

from sim.embodiment.description import DescriptionError
from teleop.retarget.hand_model import HandKinematics

# Finger sets in order of preference: a tripod is steadier on a ball than thumb and index alone,
# but not every thumb reaches two fingers at once; the first set whose pads meet is used.
FINGER_SETS = (("index", "middle"), ("index",), ("middle",))
MEET_M = 0.005                           # pads "meet" when their points are this close
FOLD_FRACTION = 0.9                      # the other fingers: this far towards their closed end
SOLVE_ITERS = 60
RANDOM_STARTS = 400
BEST_STARTS = 4
DAMPING = 1e-4


@dataclass(frozen=True)
class PinchGrasp:
    centre: np.ndarray          # object centre in the wrist-site frame (right hand)
    close: np.ndarray           # actuator targets, hand actuator order, pads meeting
    gap_m: float                # largest remaining distance between the thumb pad and a pinching pad
    fingers: tuple[str, ...]    # the fingers the thumb pinches against


def _pinch_keypoints(fingers: tuple[str, ...]) -> tuple[str, ...]:
    """The MediaPipe keypoints that the thumb's and ``fingers``' retarget points follow (the spec
    guarantees those, not finger names)."""
    return tuple(f"{'pinky' if finger == 'little' else finger}_tip" for finger in ("thumb", *fingers))


def pinch_rows(hand_name: str, fingers: tuple[str, ...]) -> tuple[int, list[int]]:
    """Rows of ``HandKinematics.points`` (row 0 is the wrist point, then ``fingertips_in_site_frame``'s
    rows) of the thumb pad and of ``fingers``' pads."""
    thumb, *tips = (1 + row for row in fingertip_rows(hand_name, _pinch_keypoints(fingers)))
    return thumb, tips


def pinch_fingers(item: dict) -> tuple[str, ...] | None:
    """A plan step's `pinch_fingers`, for a pad or a flat pinch (None: the hand's own set, `pinch_grasp`)."""
    return tuple(item["pinch_fingers"]) if item.get("pinch_fingers") else None


@functools.lru_cache(maxsize=None)
def pinch_grasp(hand_name: str, fingers: tuple[str, ...] | None = None) -> PinchGrasp:
    """The first finger set whose pads meet the thumb's, else the set that comes closest. ``fingers`` (a
    plan step's `pinch_fingers`): that set, whose pads may not reach the thumb's; they "meet" within
    MEET_M of the closest they come, so the mid-range start is taken first there too."""
    if fingers:
        closest = solve_pinch(hand_name, fingers).gap_m
        options = [solve_pinch(hand_name, fingers, meet_m=closest + MEET_M)]
    else:
        options = [solve_pinch(hand_name, f) for f in FINGER_SETS]
    meeting = [g for g in options if g.gap_m <= MEET_M]
    grasp = meeting[0] if meeting else min(options, key=lambda g: g.gap_m)
    grasp.close.flags.writeable = grasp.centre.flags.writeable = False     # cached: shared by every caller
    return grasp


def moving_and_folded(kin, rows: list[int], fold: float = FOLD_FRACTION) -> tuple[np.ndarray, np.ndarray]:
    """(actuators that move any of the given keypoint rows, the pose the others fold away to): the
    actuators that move a pinching point solve, the rest fold ``fold`` of the way to their closed end."""
    moving = np.zeros(kin.dof, bool)
    for q in (kin.home, kin.mid):     # a coupling resting on its limit hides a joint at one of them
        _, J = kin.points_and_jacobians(q)
        for row in rows:
            moving |= np.abs(J[row]).sum(axis=0) > 1e-9
    far = np.where(np.abs(kin.upper - kin.home) >= np.abs(kin.lower - kin.home), kin.upper, kin.lower)
    return moving, kin.home + fold * (far - kin.home)


def damped_step(kin, q: np.ndarray, cols, A: np.ndarray, r: np.ndarray, damping: float, gap, q_gap: float):
    """One Levenberg-Marquardt step on the joints ``cols`` (residual ``r``, its Jacobian ``A`` over those
    joints), kept within the joint ranges: taken if it shrinks ``gap`` (damping eases), else refused
    (damping grows). Returns (q, its gap, damping)."""
    step = np.linalg.solve(A.T @ A + damping * np.eye(A.shape[1]), -A.T @ r)
    trial = q.copy()
    trial[cols] = np.clip(q[cols] + step, kin.lower[cols], kin.upper[cols])
    trial_gap = gap(trial)
    if trial_gap < q_gap:
        return trial, trial_gap, max(damping / 3, DAMPING)
    return q, q_gap, min(damping * 10, 1e6)


def solve_pinch(hand_name: str, fingers: tuple[str, ...], meet_m: float = MEET_M) -> PinchGrasp:
    """Levenberg-Marquardt from the middle of the ranges, then from the best few of a seeded random
    sample (one start gets caught in local minima on the hands with little thumb opposition); the
    first start whose pads come within ``meet_m`` is taken."""
    kin = hand_kinematics(hand_name)
    thumb, tips = pinch_rows(hand_name, fingers)
    moving, folded = moving_and_folded(kin, [thumb, *tips])

    def gap(q):
        P = kin.points(q)
        return max(np.linalg.norm(P[thumb] - P[t]) for t in tips)

    samples = np.random.default_rng(0).uniform(kin.lower, kin.upper, size=(RANDOM_STARTS, kin.dof))
    starts = [kin.mid] + sorted(samples, key=gap)[:BEST_STARTS]
    best, best_gap = None, np.inf
    for start in starts:
        q = np.where(moving, start, folded)
        q_gap, damping = gap(q), DAMPING
        for _ in range(SOLVE_ITERS):       # Levenberg-Marquardt: the pads need not meet, so steps can overshoot
            P, J = kin.points_and_jacobians(q)
            r = np.concatenate([P[thumb] - P[t] for t in tips])
            A = np.concatenate([J[thumb] - J[t] for t in tips])[:, moving]
            q, q_gap, damping = damped_step(kin, q, moving, A, r, damping, gap, q_gap)
        if q_gap < best_gap:
            best, best_gap = q.copy(), q_gap
        if best_gap <= meet_m:     # the first start that meets: mid-range first, the most natural pinch
            break
    meet = kin.points(best)[[thumb, *tips]].mean(axis=0)
    return PinchGrasp(centre=kin.hand.wrist_site.to_local(meet), close=best, gap_m=float(best_gap), fingers=fingers)


@functools.lru_cache(maxsize=None)
def thumb_actuators(hand_name: str) -> np.ndarray:
    """Which of the hand's actuators (hand actuator order) move the thumb's tip."""
    kin = hand_kinematics(hand_name)
    moving, _ = moving_and_folded(kin, [1 + fingertip_rows(hand_name, (THUMB_TIP,))[0]])
    moving.flags.writeable = False      # cached: shared by every caller
    return moving


@functools.lru_cache(maxsize=None)
def hand_kinematics(hand_name: str) -> HandKinematics:
    """The hand's own kinematic model (teleop/retarget), built once per hand."""
    return HandKinematics(hand_name)


def pinch_preshape(hand_name: str, open_: np.ndarray, close: np.ndarray, width_m: float,
                   fingers: tuple[str, ...] | None = None,
                   other_gap: Callable[[np.ndarray], float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The pre-shape to come down with: actuator targets on the way from ``open_`` to ``close``, as
    closed as possible while the thumb pad stays ``width_m`` from every pinching pad (and, if given,
    ``other_gap(q)`` is at least ``width_m`` too: teleop/pinch_tips.py), and the point midway between
    the thumb pad and the pinching pads there (wrist-site frame, right hand), where the object's centre
    goes so that both sides close in on it together."""
    kin = hand_kinematics(hand_name)
    thumb, tips = pinch_rows(hand_name, pinch_grasp(hand_name, fingers).fingers)
    for s in np.linspace(1.0, 0.0, 21):      # ends at s = 0, the open hand, if nothing is wide enough
        q = open_ + s * (close - open_)
        P = kin.points(q)
        gap = min(np.linalg.norm(P[thumb] - P[t]) for t in tips)
        if other_gap is not None:
            gap = min(gap, other_gap(q))
        if gap >= width_m:
            break
    middle = 0.5 * (P[thumb] + P[tips].mean(axis=0))
    return q, kin.hand.wrist_site.to_local(middle)


def fingertips_in_site_frame(hand_name: str, q: np.ndarray) -> np.ndarray:
    """(fingers, 3) fingertip pad points of the right hand at actuator targets ``q``, in the
    wrist-site frame (x lateral, y palm normal, z along the fingers); rows in the order of the hand
    file's `retarget.fingertips` (``fingertip_rows`` finds them by keypoint)."""
    kin = hand_kinematics(hand_name)
    return kin.hand.wrist_site.to_local(kin.points(q)[1:])


THUMB_TIP = "thumb_tip"


def fingertip_rows(hand_name: str, keypoints: tuple[str, ...] | None = None) -> list[int]:
    """Rows of ``fingertips_in_site_frame`` whose retarget points follow ``keypoints`` (in that
    order), or with None every finger's but the thumb's."""
    followed = [t.keypoint for t in hand_kinematics(hand_name).spec.fingertips]
    if keypoints is None:
        return [i for i, k in enumerate(followed) if k != THUMB_TIP]
    missing = [k for k in keypoints if k not in followed]
    if missing:
        raise DescriptionError(f"{hand_kinematics(hand_name).hand.path}: field 'retarget.fingertips': expected "
                               f"points following {missing} (for a pinch, a plan step's fingers), got {followed}")
    return [followed.index(k) for k in keypoints]


@functools.lru_cache(maxsize=None)
def pinch_axis_in_site_frame(hand_name: str, fingers: tuple[str, ...] | None = None) -> np.ndarray:
    """Unit vector from the thumb pad to the pinching pads (right hand, wrist-site frame), with the
    hand half closed: the direction across which a pinched object must fit."""
    grasp = pinch_grasp(hand_name, fingers)
    kin = hand_kinematics(hand_name)
    thumb, *tips = fingertip_rows(hand_name, _pinch_keypoints(grasp.fingers))
    P = fingertips_in_site_frame(hand_name, 0.5 * (kin.home + grasp.close))
    axis = P[tips].mean(axis=0) - P[thumb]
    axis /= np.linalg.norm(axis)
    axis.flags.writeable = False        # cached: shared by every caller
    return axis
