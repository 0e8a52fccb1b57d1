"""`turn` with `palm_from`: the flat palm pushes a hinged link round, the fingers along its hinge.

How a person swings a toilet lid the last part of the way open, or pushes an open lid back over
to shut it: the hand flat, the palm square to the face and the fingers along the hinge, moving
with the face. Fingertips pushing square to a face that has turned upright need the hand turned
to point across the body (the xArm7's left hand missed such poses by 4-18 cm); with the fingers
along the hinge the wrist keeps the heading it has at rest. teleop/plan_steps/turn.py asks for
these poses once the link has passed `palm_from` along the turn. Before it the fingers, along the
hinge too, lift the link from under its edge, where a flat hand does not fit: only the fingertip
nearest the hinge goes under the edge, the others beyond it (`innermost`).
"""

from __future__ import annotations

import numpy as np

from sim.embodiment.mirror import mirror_vec
from teleop.pinch_grasp import fingertip_rows, fingertips_in_site_frame
from teleop.transit import hand_outline

PALM_REACH = 0.7              # the palm's middle at most this fraction of the handle's distance from the hinge: the
                              # whole palm on the link's face, not on its edge
PALM_CENTRE_M = 0.04          # outline points this close to the wrist site (across and along the fingers) are the palm's


def palm_point(hand_name: str, side: str, open_targets: np.ndarray) -> np.ndarray:
    """The middle of the palm's surface in the wrist-site frame (x lateral, y palm normal, z along
    the fingers): the open hand's outline reaching farthest along the palm normal near the site."""
    pts = hand_outline(hand_name, side, open_targets)
    near = pts[(np.abs(pts[:, 0]) < PALM_CENTRE_M) & (np.abs(pts[:, 2]) < PALM_CENTRE_M)]
    return np.array([0.0, float(near[:, 1].max()), 0.0])


def finger_tips(hand_name: str, side: str, open_targets: np.ndarray) -> np.ndarray:
    """(fingers, 3) the open hand's fingertips but the thumb's, wrist-site frame (mirrored for the left)."""
    tips = fingertips_in_site_frame(hand_name, open_targets)[fingertip_rows(hand_name)]
    return np.array([mirror_vec(t) for t in tips]) if side == "left" else tips


def innermost(tips: np.ndarray, R: np.ndarray, radial: np.ndarray) -> np.ndarray:
    """Of fingertips ``tips`` (wrist-site frame) spread along the link (fingers along its hinge), the one
    nearest the hinge with the hand turned ``R``: it alone goes under the link's edge, the others
    beyond it, clear of what the link closes onto (a lid's bowl)."""
    return tips[int(np.argmin((tips @ R.T) @ radial))]


def palm_frame(push: np.ndarray, fingers: np.ndarray) -> np.ndarray:
    """The wrist-site rotation (world) of a hand whose palm faces ``push`` with the fingers along
    ``fingers`` (made square to it)."""
    y = push / np.linalg.norm(push)
    z = fingers - (fingers @ y) * y
    z /= np.linalg.norm(z)
    return np.column_stack([np.cross(y, z), y, z])


def palm_turns(angle: float, palm_from: float | None, way: float) -> bool:
    """Whether the palm pushes at link ``angle``: once the turn (``way``: +1 the angle grows) has
    reached ``palm_from``."""
    return palm_from is not None and way * (angle - palm_from) >= -1e-9
