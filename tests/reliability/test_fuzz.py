"""Fuzzing (hypothesis) of what reads outside input: the ARKit datagram parser and receiver, the operator
stream file reader, the raw-recording reader and the episode reader/validator (issue 23, item 7).

Each must return a value or raise its own clear error (PacketError, StreamFileError, SpecError), never
another exception. Bounded for CI: few examples, no example database, a deadline per example."""

import json
import os
import socket
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from episodes.raw import read_raw
from episodes.reader import open_episode
from episodes.validate import validate_episode
from sim.errors import SpecError
from teleop.streams.arkit import ArkitWristReceiver, PacketError, parse_packet
from teleop.streams.recorded import StreamFileError, read_stream

# B2D_FUZZ_SCALE=20 runs twenty times the examples (a longer campaign by hand; random, not derandomized)
SCALE = int(os.environ.get("B2D_FUZZ_SCALE", "1"))
BOUNDED = settings(max_examples=60 * SCALE, deadline=2000, database=None, derandomize=SCALE == 1,
                   suppress_health_check=[HealthCheck.too_slow])
FILES = settings(BOUNDED, max_examples=15 * SCALE)

_leaf = st.one_of(st.none(), st.booleans(), st.integers(), st.integers(min_value=2**62, max_value=2**80),
                  st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=4))
_keys = st.sampled_from(["t_ns", "left", "right", "pos", "quat_wxyz", "tracked"]) | st.text(max_size=3)
_json = st.recursive(_leaf, lambda inner: st.lists(inner, max_size=5) | st.dictionaries(_keys, inner, max_size=5),
                     max_leaves=25)
_packets = st.fixed_dictionaries({"t_ns": _leaf}, optional={"left": _json, "right": _json}).map(
    lambda d: json.dumps(d).encode()) | _json.map(lambda d: json.dumps(d).encode()) | st.binary(max_size=200)


@BOUNDED
@given(_packets)
def test_arkit_parser_accepts_or_refuses_every_datagram(payload):
    try:
        t_ns, hands = parse_packet(payload)
    except PacketError:
        return
    assert 0 <= t_ns < 2**63 and hands
    for pos, quat, tracked in hands.values():
        assert pos.shape == (3,) and quat.shape == (4,) and isinstance(tracked, bool)


@settings(BOUNDED, max_examples=10 * SCALE)
@given(st.lists(_packets, min_size=1, max_size=20))
def test_a_live_receiver_survives_any_datagrams(payloads):
    """The teleop session's view: datagrams on the socket, then poll(); a bad one is counted, never raised."""
    with ArkitWristReceiver() as receiver, socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sender:
        good = b'{"t_ns": 1, "right": {"pos": [0, 0, 0.1], "quat_wxyz": [1, 0, 0, 0]}}'
        for payload in [*payloads, good]:
            sender.sendto(payload, receiver.address)
        frames = [receiver.poll() for _ in range(3)]
        assert receiver.received == len(payloads) + 1
        assert any(f is not None for f in frames)


def _mutate(data: bytes, flips: list[tuple[float, int]], cut: float | None) -> bytes:
    out = bytearray(data)
    for index, bit in {int(where * (len(out) - 1)): bit for where, bit in flips}.items():   # each byte once
        out[index] ^= 1 << bit
    return bytes(out[: int(len(out) * cut)] if cut is not None else out)


_flips = st.lists(st.tuples(st.floats(0, 1), st.integers(0, 7)), min_size=1, max_size=8)
_cut = st.none() | st.floats(0, 0.999)


@FILES
@given(_flips, _cut)
def test_raw_reader_refuses_damaged_recordings_clearly(raw_path, flips, cut):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "episode_0000.raw.h5"
        path.write_bytes(_mutate(raw_path.read_bytes(), flips, cut))
        try:
            rec = read_raw(path)
        except SpecError as exc:
            assert str(path) in str(exc)
            return
        assert rec.num_steps > 0 and np.isfinite(rec.action).all()


@FILES
@given(_flips, _cut)
def test_episode_reader_and_validator_on_damaged_episodes(episode_dir, flips, cut):
    source = episode_dir / "episode_0000.hdf5"
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / source.name
        (Path(tmp) / "episode_manifest.json").write_bytes((episode_dir / "episode_manifest.json").read_bytes())
        path.write_bytes(_mutate(source.read_bytes(), flips, cut))
        assert validate_episode(path), "a damaged episode was reported valid"     # with its manifest: always
        try:
            with open_episode(path) as reader:
                for name in ("time/frame_index", "action/action", *(f"cameras/{c}/rgb" for c in reader.camera_ids)):
                    reader.read(name)
                reader.metrics()
        except SpecError as exc:
            assert str(path) in str(exc)


@FILES
@given(st.binary(max_size=600))
def test_operator_stream_reader_refuses_junk_clearly(data):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "stream.npz"
        path.write_bytes(data)
        try:
            read_stream(path)
        except StreamFileError as exc:
            assert str(path) in str(exc)


@FILES
@given(_flips, _cut)
def test_operator_stream_reader_on_damaged_streams(recorded_stream, flips, cut):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "stream.npz"
        path.write_bytes(_mutate(recorded_stream.read_bytes(), flips, cut))
        try:
            frames = read_stream(path)
        except StreamFileError as exc:
            assert str(path) in str(exc)
            return
        assert all(f.keypoints.shape == (2, 21, 3) for f in frames)
