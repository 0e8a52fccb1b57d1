"""The `retarget:` block of a hand file: which robot points stand for the operator's hand keypoints.

DexPilot retargeting (``teleop/retarget``) compares vectors between the operator's fingertips and
wrist with the same vectors on the robot hand. This block names, per finger, the robot point that
plays the fingertip (a point on a link, in that link's frame: the centre of the distal pad, where a
pinch makes contact) and the MediaPipe keypoint it follows, the robot point that plays the wrist,
and the scale from human to robot hand size::

    retarget:
      scale: 1.41            # robot / human hand size (open-hand wrist to middle fingertip)
      wrist: {body: palm, pos: [0, 0, 0]}
      fingertips:
      - {finger: thumb, keypoint: thumb_tip, body: link_thumb_3, pos: [0, 0.0098, 0.0326]}
      - ...

The block lives in the hand file, so it is read here from the same file as ``load_hand`` (safe YAML);
its keys, types and ranges are the hand schema's (``sim.schema.hand.Retarget``), checked again here
for a block given on its own, and its bodies and fingers are checked against the parsed hand. Positions are for the RIGHT hand like the
rest of the file; the left hand is its mirror image with the same joint angles (``mirror.py``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from sim.registry import load_yaml
from sim.schema import validate
from sim.schema.hand import FINGERTIP_KEYPOINTS, Retarget

from .fields import DescriptionError
from .hand_file import HandDescription, load_hand

# The 21 MediaPipe hand landmarks, in MediaPipe's order.
MEDIAPIPE_KEYPOINTS = (
    "wrist",
    "thumb_cmc", "thumb_mcp", "thumb_ip", "thumb_tip",
    "index_mcp", "index_pip", "index_dip", "index_tip",
    "middle_mcp", "middle_pip", "middle_dip", "middle_tip",
    "ring_mcp", "ring_pip", "ring_dip", "ring_tip",
    "pinky_mcp", "pinky_pip", "pinky_dip", "pinky_tip",
)


@dataclass(frozen=True)
class RobotPoint:
    body: str              # hand link name (right-hand description)
    pos: np.ndarray        # (3,) in the link frame, metres


@dataclass(frozen=True)
class Fingertip:
    finger: str
    keypoint: str          # one of FINGERTIP_KEYPOINTS
    point: RobotPoint

    @property
    def keypoint_index(self) -> int:
        return MEDIAPIPE_KEYPOINTS.index(self.keypoint)


@dataclass(frozen=True)
class RetargetSpec:
    hand: str
    scale: float
    wrist: RobotPoint
    fingertips: tuple[Fingertip, ...]   # thumb first


def _fail(hand: HandDescription, field: str, msg: str):
    raise DescriptionError(f"{hand.path}: field 'retarget.{field}': {msg}")


def _point(point, hand: HandDescription, field: str, links: set[str]) -> RobotPoint:
    if point.body not in links:
        _fail(hand, f"{field}.body", f"expected a link of this hand {sorted(links)}, got {point.body!r}")
    return RobotPoint(point.body, np.asarray(point.pos, float))


@functools.lru_cache(maxsize=None)
def load_retarget_spec(hand_name: str) -> RetargetSpec:
    """Parse and check the `retarget:` block of a hand file."""
    hand = load_hand(hand_name)
    return parse_retarget_spec(load_yaml(hand.path).get("retarget"), hand)


def parse_retarget_spec(raw, hand: HandDescription) -> RetargetSpec:
    """Check a `retarget:` block (parsed YAML) against its hand; errors name the file and field."""
    if raw is None:
        raise DescriptionError(f"{hand.path}: field 'retarget': missing (expected scale, wrist and "
                               f"fingertips for DexPilot retargeting)")
    block = validate(Retarget, raw, hand.path, prefix="retarget", error=DescriptionError)   # keys, types, ranges
    links = {link.name for link in hand.links}
    wrist = _point(block.wrist, hand, "wrist", links)
    tips = []
    for i, t in enumerate(block.fingertips):
        field = f"fingertips[{i}]"
        if t.finger not in hand.fingers:
            _fail(hand, f"{field}.finger", f"expected one of the fingers {list(hand.fingers)}, got {t.finger!r}")
        tips.append(Fingertip(t.finger, t.keypoint, _point(t, hand, field, links)))
    fingers = [t.finger for t in tips]
    if sorted(fingers) != sorted(hand.fingers):
        _fail(hand, "fingertips", f"expected exactly one entry per finger {list(hand.fingers)}, got {fingers}")
    keypoints = [t.keypoint for t in tips]
    if len(set(keypoints)) != len(keypoints):
        _fail(hand, "fingertips", f"each keypoint may be used once, got {keypoints}")
    if "thumb_tip" not in keypoints:
        _fail(hand, "fingertips", "one fingertip must follow 'thumb_tip' (DexPilot's pinch terms need a thumb)")
    tips.sort(key=lambda t: FINGERTIP_KEYPOINTS.index(t.keypoint))    # thumb first, then MediaPipe order
    return RetargetSpec(hand=hand.name, scale=block.scale, wrist=wrist, fingertips=tuple(tips))
