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
from teleop.pinch_grasp import pinch_grasp, pinch_preshape


def tips_clear_preshape(hand_name: str, open_: np.ndarray, close: np.ndarray, width_m: float,
                        fingers: tuple[str, ...] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``pinch_preshape`` with the thumb's tip too ``width_m`` from every pinching finger's tip."""
    pinching = pinch_grasp(hand_name, fingers).fingers     # the fingers the thumb closes against

    def tip_gap(q: np.ndarray) -> float:      # thumb tip to the nearest pinching tip
        T = tip_points(hand_name, pinching, q)
        return min(float(np.linalg.norm(T[0] - T[k])) for k in range(1, len(T)))

    return pinch_preshape(hand_name, open_, close, width_m, fingers, other_gap=tip_gap)
