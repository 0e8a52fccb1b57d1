"""Manus glove adapter: the runtime's 25-node raw hand skeleton -> 21 MediaPipe keypoints.

The node mapping is data (``manus_skeleton.yaml``: node order, which node feeds which keypoint,
which nodes are dropped). Node positions may be given in any right-handed metric frame (the
Manus coordinate system the client set up); the keypoints are re-expressed in the hand's wrist
frame (``frame.py``), so the frame the glove reports in does not matter.

The Manus runtime hands skeletons to a client through its SDK (shared memory on the operator's PC);
that client is outside this repository. ``ManusStream`` takes a callable returning the newest
skeletons and turns them into operator frames. A glove measures the hand, not where it is: wrist
poses come from a tracker (``arkit.py``, merged with ``CombinedStream``) unless
``wrist_from_skeleton`` is set for a skeleton reported in a tracked world frame.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import yaml

from sim.embodiment.description import mat_to_quat
from sim.embodiment.retarget_spec import MEDIAPIPE_KEYPOINTS

from .frame import NUM_KEYPOINTS, SIDES, OperatorFrame, to_wrist_frame

MAPPING_FILE = Path(__file__).with_name("manus_skeleton.yaml")
NUM_NODES = 25


class ManusMappingError(ValueError):
    """The node mapping file is malformed."""


@dataclass(frozen=True)
class ManusMapping:
    nodes: tuple[str, ...]          # the 25 raw skeleton nodes, in the runtime's order
    node_of_keypoint: np.ndarray    # (21,) node index feeding each MediaPipe keypoint
    dropped: tuple[str, ...]
    path: Path


@functools.lru_cache(maxsize=None)
def load_manus_mapping(path: Path = MAPPING_FILE) -> ManusMapping:
    with open(path, encoding="utf-8") as f:
        data = yaml.safe_load(f)

    def fail(field, msg):
        raise ManusMappingError(f"{path}: field '{field}': {msg}")

    nodes = data.get("nodes") if isinstance(data, dict) else None
    if not isinstance(nodes, list) or len(nodes) != NUM_NODES or len(set(nodes)) != NUM_NODES:
        fail("nodes", f"expected {NUM_NODES} distinct node names")
    mapping = data.get("keypoints")
    if not isinstance(mapping, dict) or set(mapping) != set(MEDIAPIPE_KEYPOINTS):
        fail("keypoints", f"expected one entry for each of the {NUM_KEYPOINTS} MediaPipe keypoints {MEDIAPIPE_KEYPOINTS}")
    for k, node in mapping.items():
        if node not in nodes:
            fail(f"keypoints.{k}", f"expected one of the nodes, got {node!r}")
    dropped = tuple(data.get("dropped") or ())
    unused = set(nodes) - set(mapping.values())
    if set(dropped) != unused:
        fail("dropped", f"expected exactly the nodes no keypoint uses {sorted(unused)}, got {list(dropped)}")
    index = np.array([nodes.index(mapping[k]) for k in MEDIAPIPE_KEYPOINTS])
    return ManusMapping(tuple(nodes), index, dropped, Path(path))


def manus_to_keypoints(nodes: np.ndarray, side: str, mapping: ManusMapping | None = None
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(25, 3) skeleton -> (21, 3) keypoints in the wrist frame, plus the wrist frame's rotation and
    origin in the skeleton's frame."""
    mapping = mapping or load_manus_mapping()
    nodes = np.asarray(nodes, float)
    if nodes.shape != (NUM_NODES, 3):
        raise ValueError(f"Manus skeleton: expected shape ({NUM_NODES}, 3), got {nodes.shape}")
    return to_wrist_frame(nodes[mapping.node_of_keypoint], side)


class ManusStream:
    """Operator frames from a skeleton source: ``read()`` returns None (nothing new) or
    ``(timestamp_ns, {side: (25, 3) node positions or None})``."""

    def __init__(self, read: Callable[[], tuple[int, dict] | None], wrist_from_skeleton: bool = False,
                 mapping: ManusMapping | None = None):
        self.read = read
        self.wrist_from_skeleton = wrist_from_skeleton
        self.mapping = mapping or load_manus_mapping()

    def poll(self) -> OperatorFrame | None:
        sample = self.read()
        if sample is None:
            return None
        t_ns, skeletons = sample
        frame = OperatorFrame.empty(t_ns)
        for side in SIDES:
            nodes = skeletons.get(side)
            if nodes is None:
                continue
            try:
                kp, R, origin = manus_to_keypoints(nodes, side, self.mapping)
            except ValueError:
                # a non-finite or collapsed skeleton: pass it on as non-finite keypoints, so the
                # sanitizer holds the last good ones and records why
                kp, R, origin = np.full((NUM_KEYPOINTS, 3), np.nan), np.eye(3), np.full(3, np.nan)
            if self.wrist_from_skeleton:
                frame = frame.with_hand(side, keypoints=kp, wrist_pos=origin, wrist_quat=mat_to_quat(R))
            else:
                frame = frame.with_hand(side, keypoints=kp)
        return frame
