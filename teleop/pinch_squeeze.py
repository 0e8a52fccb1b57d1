"""A pinch's closed shape pressed past where its tips meet: a firmer hold on a heavy part.

A position-servoed finger presses what stops it in proportion to how far its target lies beyond
(up to its full effort). The flat pinch's closed shape puts the thumb's tip on the fingers' tips,
so on a 24 mm hammer handle the fingers stop where the handle is and press only by the distance
left to that shape: the RH56DFX's index finger at half its effort, and the 0.6 kg hammer slid out
between the tips when the arm stopped over the block. A person holding a heavier tool squeezes
harder: the step's `grasp_squeeze_m` aims the thumb's tip that far past the fingers' tips along
the pinch's axis. Of the joint motions that do so, the smallest (minimum norm, linearised at the
closed shape): it bends the joints that move the tips along the axis (the fingers' flexion), not
the ones that swing them across it (a thumb's rotation over the palm), so the tips press the part
where they hold it instead of sliding round it. No per-hand numbers.
"""

from __future__ import annotations

import numpy as np

from teleop.flat_pinch import tip_pinch, tip_points

FD_STEP = 1e-5      # rad: finite-difference step of the tips' Jacobian


def squeezed(hand_name: str, close: np.ndarray, ready: np.ndarray, depth_m: float,
             fingers: tuple[str, ...] | None = None) -> np.ndarray:
    """Actuator targets (hand order) ``depth_m`` metres of thumb-to-fingers' tip travel past ``close``
    along the pinch axis (from the thumb's tip to the fingers' at ``ready``), moving only the pinch's
    joints, by the minimum-norm step; not yet clipped to the actuator ranges. ``fingers``: the tips' pinch set
    (a plan step's `pinch_fingers`; default the hand's own)."""
    close = np.asarray(close, float)
    if depth_m <= 0.0:
        return close.copy()
    pinch = tip_pinch(hand_name, fingers)
    fingers = pinch.fingers
    P = tip_points(hand_name, fingers, ready)
    axis = P[1:].mean(axis=0) - P[0]
    axis /= np.linalg.norm(axis)

    def along(q: np.ndarray) -> float:      # the thumb's tip past the fingers' tips, along the axis
        T = tip_points(hand_name, fingers, q)
        return float((T[0] - T[1:].mean(axis=0)) @ axis)

    base = along(close)
    grad = np.zeros(len(close))
    for c in np.flatnonzero(pinch.moving):
        dq = close.copy()
        dq[c] += FD_STEP
        grad[c] = (along(dq) - base) / FD_STEP
    return close + depth_m * grad / float(grad @ grad)
