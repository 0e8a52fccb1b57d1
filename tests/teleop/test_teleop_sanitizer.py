"""Bad operator input keeps the session alive: each case generated here is held and flagged."""

from __future__ import annotations

import numpy as np
import pytest

from teleop.streams import OperatorFrame, StepFlag, StreamSanitizer
from teleop.streams.human_hand import open_hand, power_grasp

PERIOD = 16_666_667
Q = np.array([1.0, 0.0, 0.0, 0.0])


def frame(i: int, closure: float = 0.0, pos=(0.0, 0.0, 1.0), quat=Q, t=None) -> OperatorFrame:
    f = OperatorFrame.empty(PERIOD * i if t is None else t)
    for side in ("left", "right"):
        f = f.with_hand(side, keypoints=power_grasp(closure, side), wrist_pos=pos, wrist_quat=quat)
    return f


def primed() -> StreamSanitizer:
    s = StreamSanitizer(nominal_period_ns=PERIOD)
    step = s.step(frame(1, 0.2))
    assert step.flags == StepFlag.NONE and step.fresh_keypoints.all() and step.fresh_wrist.all()
    return s


def test_before_any_input_home_is_held_and_flagged():
    step = StreamSanitizer().step(None)
    assert step.flags == StepFlag.DROPPED | StepFlag.NO_INPUT_YET
    assert not step.frame.keypoints_valid.any() and not step.frame.wrist_valid.any()
    assert sum("no valid input since reset" in r for r in step.reasons) == 4


def test_dropped_step_holds_the_last_frame():
    s = primed()
    step = s.step(None)
    assert step.flags == StepFlag.DROPPED and not step.fresh_keypoints.any()
    assert np.array_equal(step.frame.keypoints[1], power_grasp(0.2)) and step.frame.keypoints_valid.all()


def test_a_timestamp_gap_is_flagged_but_the_frame_used():
    s = primed()
    step = s.step(frame(5, 0.4))
    assert step.flags == StepFlag.DROPPED and "3.0 frames missing" in step.reasons[0]
    assert np.array_equal(step.frame.keypoints[1], power_grasp(0.4))


def test_out_of_order_frames_are_discarded():
    s = primed()
    s.step(frame(3, 0.3))
    late = s.step(frame(2, 0.9))
    assert late.flags == StepFlag.OUT_OF_ORDER and "older than the last accepted" in late.reasons[0]
    assert np.array_equal(late.frame.keypoints[1], power_grasp(0.3)) and not late.fresh_wrist.any()
    assert s.step(frame(3, 0.5)).flags == StepFlag.NONE      # an equal stamp is not older


def test_nan_keypoints_hold_that_hand_only():
    s = primed()
    f = frame(2, 0.6)
    f.keypoints[1, 8] = np.nan
    step = s.step(f)
    assert step.flags == StepFlag.BAD_KEYPOINTS and step.reasons == ("right keypoints: 1 of 21 non-finite; last valid held",)
    assert np.array_equal(step.frame.keypoints[1], power_grasp(0.2))            # held
    assert np.array_equal(step.frame.keypoints[0], power_grasp(0.6, "left"))    # the other hand moves on
    assert step.fresh_keypoints.tolist() == [True, False] and step.fresh_wrist.all()


@pytest.mark.parametrize("pos, quat", [((np.nan, 0.0, 1.0), Q), ((0.0, 0.0, 1.0), (0.0, 0.0, 0.0, 0.0)),
                                       ((0.0, 0.0, 1.0), (np.inf, 0.0, 0.0, 0.0))])
def test_bad_wrist_poses_are_held(pos, quat):
    s = primed()
    step = s.step(frame(2, 0.3, pos=pos, quat=quat))
    assert step.flags == StepFlag.BAD_WRIST and len(step.reasons) == 2
    assert np.array_equal(step.frame.wrist_pos, [[0, 0, 1.0]] * 2) and np.array_equal(step.frame.wrist_quat, [Q, Q])
    assert step.fresh_keypoints.all() and not step.fresh_wrist.any()


def test_untracked_parts_are_held_and_quaternions_normalised():
    s = primed()
    f = OperatorFrame.empty(2 * PERIOD).with_hand("left", keypoints=open_hand("left"), wrist_pos=[1, 2, 3],
                                                   wrist_quat=[2.0, 0, 0, 0])
    step = s.step(f)
    assert step.flags == StepFlag.BAD_KEYPOINTS | StepFlag.BAD_WRIST
    assert step.reasons == ("right keypoints: not tracked; last valid held", "right wrist: not tracked; last valid held")
    assert np.array_equal(step.frame.wrist_quat[0], Q) and np.array_equal(step.frame.wrist_pos[0], [1, 2, 3])


def test_reset_forgets_everything():
    s = primed()
    s.reset()
    step = s.step(frame(0, 0.1))            # an earlier stamp is fine after reset
    assert step.flags == StepFlag.NONE


def test_flags_fit_the_recorders_uint8():
    assert max(StepFlag) < 256 and np.uint8(sum(StepFlag)) == sum(StepFlag)
