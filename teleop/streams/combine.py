"""One operator stream from two devices: hand keypoints from one (a glove or a webcam), wrist
poses from the other (ARKit), as in the paper's Manus + ARKit setup.

The devices stamp frames on their own clocks. Each source's clock is mapped onto the host clock by
the offset seen at its first frame, so merged frames carry comparable timestamps; a source frame
older than that source's previous one keeps its (older) stamp on the merged frame, so the
sanitizer flags it as out of order instead of it silently replacing newer data.
"""

from __future__ import annotations

import time
from typing import Callable

from .frame import OperatorFrame, OperatorStream


class CombinedStream:
    """``poll()`` returns a merged frame whenever either source delivered something (keypoints and
    their validity from the first source, wrist poses from the second), else None."""

    def __init__(self, keypoints: OperatorStream, wrists: OperatorStream,
                 clock: Callable[[], int] = time.monotonic_ns):
        self.sources = (keypoints, wrists)
        self.clock = clock
        self.offset: list[int | None] = [None, None]
        self.latest: list[OperatorFrame | None] = [None, None]
        self.latest_t: list[int | None] = [None, None]

    def poll(self) -> OperatorFrame | None:
        arrived, stale = [], []
        for i, source in enumerate(self.sources):
            frame = source.poll()
            if frame is None:
                continue
            if self.offset[i] is None:
                self.offset[i] = self.clock() - frame.timestamp_ns
            t = frame.timestamp_ns + self.offset[i]
            if self.latest_t[i] is not None and t < self.latest_t[i]:
                stale.append(t)
                continue
            arrived.append(t)
            self.latest[i], self.latest_t[i] = frame, t
        if not arrived and not stale:
            return None
        t_ns = min(stale) if stale else max(arrived)
        kp, wr = self.latest
        base = OperatorFrame.empty(t_ns)
        return OperatorFrame(
            t_ns,
            kp.keypoints if kp else base.keypoints, wr.wrist_pos if wr else base.wrist_pos,
            wr.wrist_quat if wr else base.wrist_quat, kp.keypoints_valid if kp else base.keypoints_valid,
            wr.wrist_valid if wr else base.wrist_valid,
        )
