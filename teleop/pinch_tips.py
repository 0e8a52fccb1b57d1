"""A pad pinch's pre-shape that clears the part at the fingertips, not only at the pads.

The pad pinch (teleop/pinch_grasp.py) comes down spread so that its pads are the part's width (plus
a margin) apart. A curled finger's distal link reaches past its pad and bends towards the thumb, so
its tip, the first thing to reach the part, is nearer the thumb than the pad is: on the LEAP (links
3 cm past the pads) the rim pinch's pads were 41 mm apart and its index tip 23 mm from the thumb's,
under 8 mm clear of the collar's 8 mm rim either side; on seeds where the hand came down a few mm off,
the index tip landed on the rim (21 N) and tipped the collar 45 degrees before the pinch closed, which
then held it by the thumb's middle link and lost it on the lift (shoebox_accessory_pack, seeds 0, 9, 10,
11 on the stream path). A person opens the hand until the tips clear the part.
`pinch_clear_tips: true` on a step does that: the most closed shape on the way from open to closed
whose pads and tips (the distal links' furthest points, teleop/flat_pinch.py) are all that far from
the thumb's. No per-hand numbers.
"""

from __future__ import annotations

import numpy as np

from teleop.flat_pinch import tip_points
from teleop.pinch_grasp import hand_kinematics, pinch_grasp, pinch_rows

PRESHAPE_STEPS = 21     # as pinch_preshape: shapes tried on the way from closed back to open


def tips_clear_preshape(hand_name: str, open_: np.ndarray, close: np.ndarray, width_m: float,
                        fingers: tuple[str, ...] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """As ``pinch_preshape``, with the thumb's tip too ``width_m`` from every pinching finger's tip:
    (actuator targets on the way from ``open_`` to ``close``, the point midway between the thumb's pad
    and the pinching pads there, wrist-site frame, right hand); the open hand if nothing is that wide."""
    kin = hand_kinematics(hand_name)
    fingers = pinch_grasp(hand_name, fingers).fingers
    thumb, pads = pinch_rows(hand_name, fingers)
    for s in np.linspace(1.0, 0.0, PRESHAPE_STEPS):
        q = open_ + s * (close - open_)
        P = kin.points(q)
        T = tip_points(hand_name, fingers, q)
        pad_gap = min(np.linalg.norm(P[thumb] - P[p]) for p in pads)
        tip_gap = min(np.linalg.norm(T[0] - T[k]) for k in range(1, len(T)))
        if min(pad_gap, tip_gap) >= width_m:
            break
    middle = 0.5 * (P[thumb] + P[pads].mean(axis=0))
    return q, kin.hand.wrist_site.to_local(middle)
