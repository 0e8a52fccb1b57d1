"""The two wire formats: the harness's length-prefixed JSON with base64 numpy arrays, and openpi's
msgpack-numpy (the bytes openpi's own packer makes), both carrying arrays bit for bit."""

import socket

import msgpack
import numpy as np
import pytest

from policies.remote import tcp_wire, ws_wire


def _observation():
    rng = np.random.default_rng(0)
    return {"images": {"head": rng.integers(0, 255, (2, 4, 5, 3), dtype=np.uint8)},
            "state": rng.normal(size=(2, 7)), "tick": np.int64(3), "instruction": "put the lemon on the plate"}


def test_tcp_frames_carry_arrays_bit_for_bit_behind_a_big_endian_length():
    obs = _observation()
    frame = tcp_wire.encode({"command": "get_action_chunk", "observation": obs})
    assert int.from_bytes(frame[:4], "big") == len(frame) - 4
    assert b'"__numpy_array__":true' in frame and b'"dtype":"<f8"' in frame
    back = tcp_wire.decode(frame[4:])["observation"]
    assert back["state"].tobytes() == obs["state"].tobytes() and back["state"].dtype == np.float64
    assert back["images"]["head"].tobytes() == obs["images"]["head"].tobytes()
    assert back["tick"] == 3 and back["instruction"] == obs["instruction"]


def test_tcp_reading_refuses_an_oversized_prefix_before_reading_and_names_a_malformed_frame():
    a, b = socket.socketpair()
    with a, b:
        a.sendall(tcp_wire.HEADER.pack(10_000) + b"x" * 10)
        with pytest.raises(tcp_wire.FrameError, match="length prefix of 10000 bytes, over the limit of 100"):
            tcp_wire.read_frame(b, max_bytes=100)
    a, b = socket.socketpair()
    with a, b:
        a.sendall(tcp_wire.HEADER.pack(3) + b"{x}")
        with pytest.raises(tcp_wire.FrameError, match="malformed frame: not UTF-8 JSON"):
            tcp_wire.read_frame(b)
        a.sendall(tcp_wire.encode({"v": {"__numpy_array__": True, "data": "!!", "dtype": "<f8", "shape": [1]}}))
        with pytest.raises(tcp_wire.FrameError, match="malformed numpy array"):
            tcp_wire.read_frame(b)
        a.sendall(tcp_wire.HEADER.pack(8) + b"{}")
        a.close()
        with pytest.raises(tcp_wire.FrameError, match="closed after 2 of 8 bytes"):
            tcp_wire.read_frame(b)


def test_ws_packing_is_openpis_msgpack_numpy():
    obs = _observation()
    packed = ws_wire.packb(obs)
    # the raw layout openpi_client.msgpack_numpy produces: bytes keys, raw data, dtype string, shape
    raw = msgpack.unpackb(packed)
    assert raw["state"] == {b"__ndarray__": True, b"data": obs["state"].tobytes(), b"dtype": "<f8", b"shape": [2, 7]}
    assert raw["tick"] == {b"__npgeneric__": True, b"data": 3, b"dtype": "<i8"}
    back = ws_wire.unpackb(packed)
    assert back["state"].tobytes() == obs["state"].tobytes()
    assert back["images"]["head"].tobytes() == obs["images"]["head"].tobytes() and back["tick"] == 3
    with pytest.raises(ValueError, match="Unsupported dtype"):
        ws_wire.packb({"x": np.array([object()])})
