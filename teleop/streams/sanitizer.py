"""Bad operator input keeps a session alive: hold the last valid target and flag the step.

Once per control step the session hands the sanitizer whatever the stream delivered (a frame, or
None when nothing arrived). It returns a frame in which every hand part is either fresh and valid
or the last valid value held, the step's ``StepFlag`` bits (they fit the recorder's uint8
``step_flags``) and human-readable reasons. What is handled:

* dropped frames: nothing arrived this step, or the timestamps jump by more than
  ``max_gap_factor`` nominal periods (frames lost in transport; the frame itself is used). Given
  the step's time on the stream's clock (``now_ns``) and a nominal period, a step without a frame
  is a drop only once the next frame is due (``late_factor`` periods since the last one; just
  under 1 so timestamps rounded to the nanosecond still count), so a stream slower than the
  control rate is not flagged between its frames;
* out-of-order frames: a timestamp older than the last accepted one; the frame is discarded;
* non-finite keypoints, or a non-finite / zero-length wrist pose, or a part the device reports as
  untracked: that part is held;
* before any valid value since ``reset`` a part has nothing to hold: ``NO_INPUT_YET`` tells the
  commander to keep the robot at home.

Unreachable wrist poses are judged by the arm IK (``teleop/retarget/command.py``), which uses the
same flags.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from .frame import NUM_KEYPOINTS, SIDES, OperatorFrame


class StepFlag(enum.IntFlag):
    NONE = 0
    DROPPED = 1          # no new frame this step, or frames lost between two frames
    OUT_OF_ORDER = 2     # a frame older than the last accepted one (discarded)
    BAD_KEYPOINTS = 4    # non-finite or untracked keypoints: the hand's last valid keypoints held
    BAD_WRIST = 8        # non-finite, zero-length or untracked wrist pose: the last valid pose held
    UNREACHABLE = 16     # the arm cannot reach the wrist pose: the last arm target held
    NO_INPUT_YET = 32    # a part has had no valid value since reset: home held


@dataclass(frozen=True)
class SanitizedStep:
    frame: OperatorFrame         # fresh or held values; *_valid = a value exists (fresh or held)
    flags: StepFlag
    reasons: tuple[str, ...]
    fresh_keypoints: np.ndarray  # (2,) bool: this step brought new valid keypoints for the hand
    fresh_wrist: np.ndarray      # (2,) bool


class StreamSanitizer:
    def __init__(self, nominal_period_ns: int | None = None, max_gap_factor: float = 2.5,
                 late_factor: float = 0.9):
        self.nominal_period_ns = nominal_period_ns
        self.max_gap_factor = max_gap_factor
        self.late_factor = late_factor
        self.reset()

    def reset(self) -> None:
        self.last_t: int | None = None
        self.keypoints = np.zeros((2, NUM_KEYPOINTS, 3))
        self.wrist_pos = np.zeros((2, 3))
        self.wrist_quat = np.tile([1.0, 0.0, 0.0, 0.0], (2, 1))
        self.has_keypoints = np.zeros(2, bool)
        self.has_wrist = np.zeros(2, bool)

    def _held(self, t_ns: int) -> OperatorFrame:
        return OperatorFrame(t_ns, self.keypoints.copy(), self.wrist_pos.copy(), self.wrist_quat.copy(),
                             self.has_keypoints.copy(), self.has_wrist.copy())

    def _overdue(self, now_ns: int | None) -> bool:
        """A step without a frame is a drop: always without a clock (every step expects a frame),
        else only when the next frame is due."""
        if now_ns is None or not self.nominal_period_ns or self.last_t is None:
            return True
        return now_ns - self.last_t >= self.late_factor * self.nominal_period_ns

    def step(self, frame: OperatorFrame | None, now_ns: int | None = None) -> SanitizedStep:
        flags, reasons = StepFlag.NONE, []
        fresh_kp, fresh_wr = np.zeros(2, bool), np.zeros(2, bool)
        if frame is None:
            if self._overdue(now_ns):
                flags |= StepFlag.DROPPED
                reasons.append("dropped: no new frame this step" if now_ns is None or self.last_t is None else
                               f"dropped: no new frame for {(now_ns - self.last_t) / 1e6:.1f} ms")
        elif self.last_t is not None and frame.timestamp_ns < self.last_t:
            flags |= StepFlag.OUT_OF_ORDER
            reasons.append(f"out of order: t={frame.timestamp_ns} ns is {self.last_t - frame.timestamp_ns} ns "
                           f"older than the last accepted frame; discarded")
            frame = None
        else:
            if self.last_t is not None and self.nominal_period_ns:
                gap = frame.timestamp_ns - self.last_t
                if gap > self.max_gap_factor * self.nominal_period_ns:
                    flags |= StepFlag.DROPPED
                    reasons.append(f"dropped: {gap / self.nominal_period_ns - 1:.1f} frames missing before "
                                   f"t={frame.timestamp_ns} ns")
            self.last_t = frame.timestamp_ns
            for i, side in enumerate(SIDES):
                flags |= self._take_keypoints(frame, i, side, fresh_kp, reasons)
                flags |= self._take_wrist(frame, i, side, fresh_wr, reasons)
        for i, side in enumerate(SIDES):
            for part, has in (("keypoints", self.has_keypoints[i]), ("wrist", self.has_wrist[i])):
                if not has:
                    flags |= StepFlag.NO_INPUT_YET
                    reasons.append(f"{side} {part}: no valid input since reset; home held")
        t_ns = self.last_t if self.last_t is not None else 0
        return SanitizedStep(self._held(t_ns), flags, tuple(reasons), fresh_kp, fresh_wr)

    def _take_keypoints(self, frame, i, side, fresh, reasons) -> StepFlag:
        if not frame.keypoints_valid[i]:
            if self.has_keypoints[i]:
                reasons.append(f"{side} keypoints: not tracked; last valid held")
                return StepFlag.BAD_KEYPOINTS
            return StepFlag.NONE     # never had any: NO_INPUT_YET says so
        kp = np.asarray(frame.keypoints[i], float)
        bad = ~np.isfinite(kp)
        if bad.any():
            reasons.append(f"{side} keypoints: {int(bad.any(axis=1).sum())} of {NUM_KEYPOINTS} non-finite; "
                           f"last valid held")
            return StepFlag.BAD_KEYPOINTS
        self.keypoints[i], self.has_keypoints[i], fresh[i] = kp, True, True
        return StepFlag.NONE

    def _take_wrist(self, frame, i, side, fresh, reasons) -> StepFlag:
        if not frame.wrist_valid[i]:
            if self.has_wrist[i]:
                reasons.append(f"{side} wrist: not tracked; last valid held")
                return StepFlag.BAD_WRIST
            return StepFlag.NONE
        pos, quat = np.asarray(frame.wrist_pos[i], float), np.asarray(frame.wrist_quat[i], float)
        norm = float(np.linalg.norm(quat)) if np.all(np.isfinite(quat)) else float("nan")
        if not np.all(np.isfinite(pos)) or not norm > 1e-6:
            reasons.append(f"{side} wrist: pose not finite or quaternion of zero length; last valid held")
            return StepFlag.BAD_WRIST
        self.wrist_pos[i], self.wrist_quat[i] = pos, quat / norm
        self.has_wrist[i], fresh[i] = True, True
        return StepFlag.NONE
