"""Operator streams: the frame type, the Manus, ARKit, recorded-file and webcam adapters, and
merging two devices. All input is generated here (keypoints of the parametric hand, real UDP
datagrams over loopback, files in a temporary folder)."""

from __future__ import annotations

import importlib.util
import json
import socket
import time

import numpy as np
import pytest
import yaml

from sim.embodiment.description import Transform, mat_to_quat, rpy_to_matrix
from teleop.streams import CombinedStream, OperatorFrame, RecordedStream, read_stream, write_stream
from teleop.streams.arkit import ArkitWristReceiver, PacketError, parse_packet
from teleop.streams.frame import KP, to_wrist_frame, wrist_frame_from_keypoints
from teleop.streams.human_hand import open_hand, pinch, power_grasp
from teleop.streams.manus import (MAPPING_FILE, ManusMappingError, ManusStream, load_manus_mapping,
                                  manus_to_keypoints)
from teleop.streams.recorded import StreamFileError
from teleop.streams.webcam import WebcamHandStream, WebcamUnavailable, landmarks_to_frame

POSE = Transform(np.array([0.4, -0.3, 1.2]), rpy_to_matrix([0.4, -0.7, 2.1]))


def in_tracker(kp_wrist: np.ndarray, T: Transform = POSE) -> np.ndarray:
    return kp_wrist @ T.rot.T + T.pos


# ---------------------------------------------------------------- frame and the parametric hand

@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("make", [open_hand, lambda side: pinch(side=side), lambda side: power_grasp(0.7, side)])
def test_wrist_frame_recovers_pose_and_keypoints(side, make):
    kp = make(side)
    local, R, origin = to_wrist_frame(in_tracker(kp), side)
    assert np.allclose(local, kp, atol=1e-12)
    assert np.allclose(R, POSE.rot, atol=1e-12) and np.allclose(origin, POSE.pos, atol=1e-12)


def test_human_hand_follows_the_wrist_frame_convention():
    right, left = open_hand("right"), open_hand("left")
    assert right[KP["thumb_tip"], 0] < 0 < left[KP["thumb_tip"], 0]          # thumb on -x (right), +x (left)
    assert np.allclose(wrist_frame_from_keypoints(right, "right")[0], np.eye(3), atol=1e-12)
    closed = power_grasp(1.0)
    assert closed[KP["index_tip"], 1] > right[KP["index_tip"], 1] + 0.05        # fingers curl towards +y
    assert np.linalg.norm(pinch()[KP["thumb_tip"]] - pinch()[KP["index_tip"]]) == pytest.approx(0.012)


def test_frame_rejects_wrong_shapes():
    f = OperatorFrame.empty(0)
    with pytest.raises(ValueError, match="keypoints"):
        OperatorFrame(0, np.zeros((2, 20, 3)), f.wrist_pos, f.wrist_quat, f.keypoints_valid, f.wrist_valid)
    with pytest.raises(ValueError, match="both wrist_pos and wrist_quat"):
        f.with_hand("right", wrist_pos=[0, 0, 0])
    with pytest.raises(ValueError, match="side"):
        f.with_hand("middle", keypoints=open_hand())


# ---------------------------------------------------------------- Manus

def manus_skeleton(kp: np.ndarray) -> np.ndarray:
    """25 Manus nodes from 21 keypoints: the four finger metacarpal (CMC) nodes MediaPipe lacks are
    placed a quarter of the way from the wrist to each MCP."""
    mapping = load_manus_mapping()
    nodes = np.full((25, 3), np.nan)
    nodes[mapping.node_of_keypoint] = kp
    for finger, mp_name in (("index", "index"), ("middle", "middle"), ("ring", "ring"), ("little", "pinky")):
        nodes[mapping.nodes.index(f"{finger}_metacarpal")] = kp[KP["wrist"]] + 0.25 * (kp[KP[f"{mp_name}_mcp"]] - kp[KP["wrist"]])
    return nodes


def test_manus_mapping_drops_the_four_finger_metacarpals():
    m = load_manus_mapping()
    assert m.dropped == ("index_metacarpal", "middle_metacarpal", "ring_metacarpal", "little_metacarpal")
    assert len(set(m.node_of_keypoint.tolist())) == 21 and m.nodes[m.node_of_keypoint[KP["thumb_cmc"]]] == "thumb_metacarpal"


@pytest.mark.parametrize("side", ["left", "right"])
def test_manus_skeleton_to_keypoints(side):
    kp = power_grasp(0.4, side)
    nodes = manus_skeleton(in_tracker(kp))
    local, R, origin = manus_to_keypoints(nodes, side)
    assert np.allclose(local, kp, atol=1e-12) and np.allclose(R, POSE.rot, atol=1e-12)
    with pytest.raises(ValueError, match=r"\(25, 3\)"):
        manus_to_keypoints(nodes[:21], side)


def test_manus_stream_frames_and_bad_skeletons():
    samples = [None, (100, {"right": manus_skeleton(in_tracker(open_hand())), "left": None}),
               (200, {"right": np.full((25, 3), np.nan)})]
    stream = ManusStream(lambda: samples.pop(0), wrist_from_skeleton=True)
    assert stream.poll() is None
    f = stream.poll()
    assert f.timestamp_ns == 100 and f.keypoints_valid.tolist() == [False, True] and f.wrist_valid.tolist() == [False, True]
    assert np.allclose(f.keypoints[1], open_hand(), atol=1e-12) and np.allclose(f.wrist_pos[1], POSE.pos)
    assert np.allclose(abs(f.wrist_quat[1] @ mat_to_quat(POSE.rot)), 1.0)
    bad = stream.poll()       # a NaN skeleton is passed on as non-finite keypoints for the sanitizer
    assert bad.keypoints_valid[1] and np.isnan(bad.keypoints[1]).all()


def test_manus_mapping_file_errors(tmp_path):
    data = yaml.safe_load(MAPPING_FILE.read_text())
    data["keypoints"]["index_tip"] = "index_nail"
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(data))
    with pytest.raises(ManusMappingError, match=r"bad.yaml: field 'keypoints.index_tip'"):
        load_manus_mapping(bad)
    data = yaml.safe_load(MAPPING_FILE.read_text())
    data["dropped"] = ["index_metacarpal"]
    bad.write_text(yaml.safe_dump(data))
    load_manus_mapping.cache_clear()
    with pytest.raises(ManusMappingError, match="field 'dropped'"):
        load_manus_mapping(bad)


# ---------------------------------------------------------------- recorded stream files

def session(n: int = 6) -> list[OperatorFrame]:
    frames = []
    for i in range(n):
        f = OperatorFrame.empty(1_000 + 16_666_667 * i)
        f = f.with_hand("right", keypoints=power_grasp(i / n), wrist_pos=POSE.pos + [0.01 * i, 0, 0],
                        wrist_quat=mat_to_quat(POSE.rot))
        if i % 2:
            f = f.with_hand("left", keypoints=pinch(side="left"))
        frames.append(f)
    frames[-1].keypoints[1, 5] = np.nan         # bad input is stored as it arrived
    return frames


def test_recorded_stream_round_trip_is_exact(tmp_path):
    frames = session()
    path = write_stream(tmp_path / "s.npz", frames)
    again = read_stream(path)
    assert len(again) == len(frames) and not list(tmp_path.glob(".*tmp*"))
    for a, b in zip(frames, again):
        assert a.timestamp_ns == b.timestamp_ns
        for name in ("keypoints", "wrist_pos", "wrist_quat", "keypoints_valid", "wrist_valid"):
            assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name
    write_stream(tmp_path / "t.npz", again)
    assert (tmp_path / "s.npz").read_bytes() == (tmp_path / "t.npz").read_bytes()


def test_recorded_stream_playback_modes(tmp_path):
    path = write_stream(tmp_path / "s.npz", session(4))
    by_step = RecordedStream(path)
    assert [by_step.poll().timestamp_ns for _ in range(4)] == [f.timestamp_ns for f in session(4)]
    assert by_step.poll() is None and by_step.done()
    timed = RecordedStream(path)
    t = [f.timestamp_ns for f in timed.frames]
    assert timed.poll(now_ns=t[0] - 1) is None                       # nothing yet: a dropped step
    assert timed.poll(now_ns=t[2]).timestamp_ns == t[2]               # the newest up to now
    assert timed.poll(now_ns=t[2]) is None


def test_recorded_stream_bad_files(tmp_path):
    path = write_stream(tmp_path / "s.npz", session(3))
    arrays = dict(np.load(path))
    arrays["keypoints"] = arrays["keypoints"][:, :, :20]
    np.savez(tmp_path / "shape.npz", **arrays)
    with pytest.raises(StreamFileError, match=r"shape.npz: field 'keypoints': expected .*\(T, 2, 21, 3\)"):
        read_stream(tmp_path / "shape.npz")
    del arrays["wrist_valid"]
    arrays["keypoints"] = np.zeros((3, 2, 21, 3))
    np.savez(tmp_path / "missing.npz", **arrays)
    with pytest.raises(StreamFileError, match="field 'wrist_valid': missing"):
        read_stream(tmp_path / "missing.npz")
    arrays = dict(np.load(path))
    arrays["timestamp_ns"] = np.array([object()] * 3, dtype=object)   # a pickled array is never loaded
    np.savez(tmp_path / "pickle.npz", **arrays)
    with pytest.raises(StreamFileError, match="pickle.npz"):
        read_stream(tmp_path / "pickle.npz")
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(StreamFileError, match="junk.npz: not a readable NPZ"):
        read_stream(tmp_path / "junk.npz")
    (tmp_path / "empty.npz").write_bytes(b"")
    with pytest.raises(StreamFileError, match="empty.npz: not a readable NPZ"):
        read_stream(tmp_path / "empty.npz")
    np.save(tmp_path / "one_array.npy", arrays["keypoints"])
    with pytest.raises(StreamFileError, match="one_array.npy: not a readable NPZ"):
        read_stream(tmp_path / "one_array.npy")


# ---------------------------------------------------------------- ARKit over UDP (loopback)

def send(address, payloads):
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        for p in payloads:
            s.sendto(p if isinstance(p, bytes) else json.dumps(p).encode(), address)


def receive(rx, tries: int = 200):
    for _ in range(tries):
        frame = rx.poll()
        if frame is not None:
            return frame
        time.sleep(0.005)
    raise AssertionError("no frame arrived over loopback")


def test_arkit_receiver_binds_loopback_and_reads_real_packets():
    q = mat_to_quat(POSE.rot)
    with ArkitWristReceiver() as rx:
        host, port = rx.address
        assert host == "127.0.0.1" and port > 0
        send(rx.address, [b"{not json", {"t_ns": 5, "right": {"pos": [1, 2], "quat_wxyz": [1, 0, 0, 0]}},
                          {"t_ns": 20, "right": {"pos": POSE.pos.tolist(), "quat_wxyz": q.tolist()},
                           "left": {"pos": [0, 0, 0], "quat_wxyz": [1, 0, 0, 0], "tracked": False}},
                          {"t_ns": 10, "right": {"pos": [9, 9, 9], "quat_wxyz": [1, 0, 0, 0]}}])
        time.sleep(0.05)
        frame = receive(rx)
        assert frame.timestamp_ns == 20                    # the newest datagram of the batch
        assert frame.wrist_valid.tolist() == [False, True] and not frame.keypoints_valid.any()
        assert np.allclose(frame.wrist_pos[1], POSE.pos) and np.allclose(frame.wrist_quat[1], q)
        assert rx.rejected == 2 and "right.pos" in rx.last_error
        assert rx.poll() is None


def test_arkit_device_to_wrist_offset():
    strap = Transform(np.array([0.0, -0.03, 0.02]), rpy_to_matrix([0.0, 0.0, np.pi / 2]))
    with ArkitWristReceiver(device_to_wrist={"right": strap}) as rx:
        send(rx.address, [{"t_ns": 1, "right": {"pos": POSE.pos.tolist(), "quat_wxyz": mat_to_quat(POSE.rot).tolist()}}])
        frame = receive(rx)
    expected = POSE @ strap
    assert np.allclose(frame.wrist_pos[1], expected.pos) and np.allclose(abs(frame.wrist_quat[1] @ expected.quat), 1.0)


@pytest.mark.parametrize("packet, field", [
    ({"right": {"pos": [0, 0, 0], "quat_wxyz": [1, 0, 0, 0]}}, "t_ns"),
    ({"t_ns": 1.5, "right": {}}, "t_ns"),
    ({"t_ns": 1}, "left"),
    ({"t_ns": 1, "right": {"pos": [0, 0, 0], "quat_wxyz": [1, 0, 0]}}, "right.quat_wxyz"),
    ({"t_ns": 1, "right": {"pos": [True, 0, 0], "quat_wxyz": [1, 0, 0, 0]}}, "right.pos"),
    ({"t_ns": 1, "right": {"pos": [0, 0, 0], "quat_wxyz": [1, 0, 0, 0], "tracked": "yes"}}, "right.tracked"),
])
def test_arkit_packet_errors_name_the_field(packet, field):
    with pytest.raises(PacketError, match=field):
        parse_packet(json.dumps(packet).encode())


# ---------------------------------------------------------------- webcam (optional extra)

def test_webcam_reports_a_missing_model_file(tmp_path):
    with pytest.raises(WebcamUnavailable, match=r"hand_landmarker.task.*|model not found"):
        WebcamHandStream(tmp_path / "hand_landmarker.task")


@pytest.mark.skipif(importlib.util.find_spec("mediapipe") is not None, reason="mediapipe is installed here")
def test_webcam_reports_the_missing_package(tmp_path):
    model = tmp_path / "hand_landmarker.task"
    model.write_bytes(b"\0")      # only its existence is checked before the package
    with pytest.raises(WebcamUnavailable, match="mediapipe"):
        WebcamHandStream(model)


def test_webcam_landmarks_to_frame():
    # MediaPipe world landmarks: metric, centred near the hand, in the camera's axes
    hands = [("Left", in_tracker(pinch(side="left"))), ("Right", in_tracker(power_grasp(0.3), POSE @ POSE))]
    frame = landmarks_to_frame(7, hands)
    assert frame.keypoints_valid.all() and not frame.wrist_valid.any()
    assert np.allclose(frame.keypoints[0], pinch(side="left")) and np.allclose(frame.keypoints[1], power_grasp(0.3))
    with pytest.raises(ValueError, match="handedness"):
        landmarks_to_frame(7, [("Both", in_tracker(open_hand()))])
    collapsed = landmarks_to_frame(8, [("Right", np.zeros((21, 3)))])    # a degenerate detection
    assert collapsed.keypoints_valid[1] and np.isnan(collapsed.keypoints[1]).all()


# ---------------------------------------------------------------- two devices, one stream

class ListStream:
    def __init__(self, frames):
        self.frames = list(frames)

    def poll(self):
        return self.frames.pop(0) if self.frames else None


def test_combined_stream_merges_glove_and_tracker():
    glove = [OperatorFrame.empty(t).with_hand("right", keypoints=power_grasp(c)) for t, c in ((1_000, 0.1), (2_000, 0.2))]
    glove.insert(1, None)
    tracker = [OperatorFrame.empty(t).with_hand("right", wrist_pos=[0, 0, t * 1e-6], wrist_quat=[1, 0, 0, 0])
               for t in (50_000, 60_000, 40_000)]                 # its own clock; the last one is late
    clock = iter([10_000_000, 20_000_000])                          # host clock at each source's first frame
    merged = CombinedStream(ListStream(glove), ListStream(tracker), clock=lambda: next(clock))
    a, b, c = merged.poll(), merged.poll(), merged.poll()
    assert a.keypoints_valid[1] and a.wrist_valid[1] and np.allclose(a.keypoints[1], power_grasp(0.1))
    assert a.timestamp_ns == 20_000_000
    assert b.timestamp_ns == 20_010_000 and np.allclose(b.wrist_pos[1], [0, 0, 0.06])
    assert c.timestamp_ns == 19_990_000                              # the late tracker frame keeps its old stamp
    assert np.allclose(c.wrist_pos[1], [0, 0, 0.06]) and np.allclose(c.keypoints[1], power_grasp(0.2))
    assert merged.poll() is None
