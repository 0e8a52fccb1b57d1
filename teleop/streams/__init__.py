"""Operator streams: the per-frame hand keypoints and wrist poses every input device is turned into
(``frame.py``), the device adapters (Manus glove, ARKit over UDP, webcam through MediaPipe, recorded
files), merging two devices, and the sanitizer that keeps a session alive on bad input."""

from .combine import CombinedStream
from .frame import SIDES, OperatorFrame, OperatorStream, to_wrist_frame, wrist_frame_from_keypoints
from .recorded import RecordedStream, read_stream, write_stream
from .sanitizer import SanitizedStep, StepFlag, StreamSanitizer

__all__ = [
    "SIDES", "CombinedStream", "OperatorFrame", "OperatorStream", "RecordedStream", "SanitizedStep", "StepFlag",
    "StreamSanitizer", "read_stream", "to_wrist_frame", "wrist_frame_from_keypoints", "write_stream",
]
