"""Generated operator streams for the session tests (imported by them), and the session-side stream
handling: the input specs, the stream clock and the sanitizer's drop test against that clock."""

from __future__ import annotations

import time

import numpy as np
import pytest

from sim.embodiment.description import Transform, mat_to_quat, rpy_to_matrix
from teleop.session_driver import session_time_ns
from teleop.session_inputs import BackgroundPoller, InputError, open_input, recorded_period_ns
from teleop.streams import OperatorFrame, StepFlag, StreamSanitizer, write_stream
from teleop.streams.human_hand import open_hand, pinch

ANCHOR = Transform(np.array([0.3, -0.2, 1.1]), rpy_to_matrix([0.3, -0.5, 1.0]))     # tracker frame
FAR = Transform(np.array([0.0, 0.0, 3.0]), np.eye(3))                               # 3 m: out of reach

# The bad frames of ``bad_stream`` (frame k is due at control step k of a session started at 0)
DROPPED = (50, 51, 52, 53)       # never sent
STALE_AFTER = 79                 # a stale copy of frame 70 arrives right after frame 79 (same step)
NAN_KEYPOINTS = 100              # right hand keypoints partly NaN
UNREACHABLE = 120                # both wrists 3 m along the fingers


def clean_frame(k: int, frames: int) -> OperatorFrame:
    """Frame k of a smooth session: the hands close from open into a pinch while the wrists drift a
    few centimetres and turn a little (hand frame)."""
    s = min(1.0, k / max(frames - 1, 1))
    move = Transform(np.array([0.04, -0.03, 0.05]) * s, rpy_to_matrix(np.array([0.1, -0.15, 0.1]) * s))
    wrist = ANCHOR @ move
    f = OperatorFrame.empty(session_time_ns(k))
    for side in ("left", "right"):
        kp = (1 - s) * open_hand(side) + s * pinch(side=side)
        f = f.with_hand(side, keypoints=kp, wrist_pos=wrist.pos, wrist_quat=mat_to_quat(wrist.rot))
    return f


def bad_stream(path, frames: int = 200):
    """A 60 Hz stream with every kind of bad input: dropped frames, an out-of-order frame, NaN
    keypoints and an unreachable wrist pose. Returns the path."""
    out = []
    for k in range(frames):
        if k in DROPPED:
            continue
        f = clean_frame(k, frames)
        if k == NAN_KEYPOINTS:
            f.keypoints[1, 4:9] = np.nan
        if k == UNREACHABLE:
            far = ANCHOR @ FAR
            f.wrist_pos[:] = far.pos
            f.wrist_quat[:] = mat_to_quat(far.rot)
        out.append(f)
        if k == STALE_AFTER:
            out.append(clean_frame(70, frames))
    return write_stream(path, out)


def expected_flags(frames: int = 200) -> dict[int, int]:
    """Step -> StepFlag bits ``bad_stream`` causes when frame k is due at recorded step k."""
    flags = {k: StepFlag.DROPPED for k in DROPPED}
    flags[DROPPED[-1] + 1] = StepFlag.DROPPED          # the next frame arrives after a gap
    flags[STALE_AFTER] = StepFlag.OUT_OF_ORDER       # arrived last in that step: judged, discarded
    flags[NAN_KEYPOINTS] = StepFlag.BAD_KEYPOINTS
    flags[UNREACHABLE] = StepFlag.UNREACHABLE
    return {k: int(v) for k, v in flags.items()}


# ---------------------------------------------------------------- tests of the session-side stream handling


def test_recorded_input_clock_and_period(tmp_path):
    source = open_input([f"recorded:{bad_stream(tmp_path / 's.npz')}"])
    assert source.name == "recorded" and source.recorded is not None
    assert source.nominal_period_ns == recorded_period_ns(source.recorded)
    assert abs(source.nominal_period_ns - 1e9 / 60) < 1
    assert open_input([f"recorded:{tmp_path / 's.npz'}"], stream_hz=30).nominal_period_ns == 33_333_333


@pytest.mark.parametrize("specs, words", [
    (["tape:x"], "expected one of recorded:PATH.npz"),
    (["recorded:/nonexistent/s.npz"], "no recorded stream file"),
    (["arkit:many"], "UDP port number"),
    (["manus:"], "Manus Core SDK"),
    (["webcam:/nonexistent/hand_landmarker.task"], "model not found"),
    (["recorded:a.npz", "arkit:0"], "give it alone"),
])
def test_bad_input_specs_say_what_was_expected(specs, words):
    with pytest.raises(InputError, match=words):
        open_input(specs)


def test_a_file_that_is_not_a_stream_names_itself(tmp_path):
    bad = tmp_path / "notes.npz"
    np.savez(bad, timestamp_ns=np.arange(3))
    with pytest.raises(InputError, match=r"notes\.npz: field 'format'"):
        open_input([f"recorded:{bad}"])


def test_arkit_and_merged_inputs_open_on_loopback():
    source = open_input(["arkit:0"])
    try:
        assert source.name == "arkit" and source.stream.address[0] == "127.0.0.1" and source.recorded is None
    finally:
        source.close()
    merged = open_input(["arkit:0", "arkit:0"], stream_hz=60)
    try:
        assert merged.name == "arkit+arkit" and merged.nominal_period_ns == 16_666_667
    finally:
        merged.close()


def test_a_slow_stream_is_not_flagged_between_its_frames_but_a_late_one_is():
    period = session_time_ns(2)      # 30 Hz against 60 Hz control
    s = StreamSanitizer(period)
    first = clean_frame(0, 10)
    assert s.step(first, 0).flags == StepFlag.NONE
    held = s.step(None, session_time_ns(1))                                    # between frames: just held
    assert held.flags == StepFlag.NONE and np.array_equal(held.frame.keypoints, first.keypoints)
    late = s.step(None, session_time_ns(2))                                    # the next frame was due
    assert late.flags == StepFlag.DROPPED and "no new frame for 33.3 ms" in late.reasons[0]
    assert StreamSanitizer(period).step(None).flags & StepFlag.DROPPED        # without a clock: as before


class Camera:
    """A blocking device: each read waits a while, like a webcam waiting for its next image."""

    def __init__(self, frames, fail_at_end: bool = False):
        self.left, self.fail_at_end = list(frames), fail_at_end

    def poll(self):
        time.sleep(0.005)
        if not self.left and self.fail_at_end:
            raise OSError("camera unplugged")
        return self.left.pop(0) if self.left else None


def wait_until_read(camera: Camera, timeout_s: float = 5.0) -> None:
    deadline = time.monotonic() + timeout_s
    while camera.left and time.monotonic() < deadline:
        time.sleep(0.005)
    time.sleep(0.05)         # the reader stores the last frame it took


def test_background_poller_returns_the_newest_frame_once():
    frames = [clean_frame(k, 5) for k in range(5)]
    camera = Camera(frames)
    poller = BackgroundPoller(camera, "camera")
    try:
        wait_until_read(camera)
        newest = poller.poll()
        assert newest is not None and newest.timestamp_ns == frames[-1].timestamp_ns
        assert poller.poll() is None          # nothing new since
    finally:
        poller.close()


def test_a_failing_device_stops_the_session_with_its_error():
    camera = Camera([clean_frame(0, 2)], fail_at_end=True)
    poller = BackgroundPoller(camera, "camera")
    try:
        wait_until_read(camera)
        with pytest.raises(RuntimeError, match="input reader stopped: camera unplugged"):
            poller.poll()
    finally:
        poller.close()
