"""The evaluation harness's TCP wire format: each message a 4-byte big-endian length, then that many bytes of
UTF-8 JSON. numpy arrays travel as {"__numpy_array__": true, "data": base64 of the raw bytes, "dtype",
"shape"}, so float64 states and actions cross the wire bit for bit.

Requests are {"command": ..., ...}: `reset` {seed, instruction}, `get_action_chunk` {observation,
instruction}, `update_after_action` {executed}, `close`; b2d adds `get_spec` (the policy's observation and
action specs). Replies are {"result": ...} or {"error": message}.

A length over the limit is refused before anything is read, so a wrong or hostile prefix cannot make
either side allocate gigabytes.
"""

from __future__ import annotations

import base64
import json
import socket
import struct

import numpy as np

DEFAULT_MAX_BYTES = 64 * 1024 * 1024    # four 640x480 views x 3 frames in base64 is about 15 MB
HEADER = struct.Struct(">I")


class FrameError(Exception):
    """A frame that cannot be read: closed mid-way, over the size limit, or not UTF-8 JSON."""


class PeerClosed(FrameError):
    """The other side hung up between messages (before the first byte of a frame)."""


def _to_json(value):
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "OVUSc":
            raise TypeError(f"arrays of dtype {value.dtype} cannot be sent")
        arr = np.ascontiguousarray(value)
        return {"__numpy_array__": True, "data": base64.b64encode(arr.tobytes()).decode("ascii"),
                "dtype": arr.dtype.str, "shape": list(arr.shape)}
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def _from_json(obj: dict):
    if obj.get("__numpy_array__") is True:
        try:
            dtype = np.dtype(obj["dtype"])
            if dtype.kind in "OV":
                raise ValueError(f"dtype {dtype} is not a plain numeric type")
            return np.frombuffer(base64.b64decode(obj["data"]), dtype=dtype).reshape(obj["shape"]).copy()
        except (KeyError, TypeError, ValueError) as exc:
            raise FrameError(f"a malformed numpy array ({type(exc).__name__}: {exc})") from exc
    return obj


def encode(message: dict) -> bytes:
    """A message as one frame (length prefix + JSON)."""
    body = json.dumps(message, default=_to_json, separators=(",", ":"), ensure_ascii=False).encode("utf-8")
    return HEADER.pack(len(body)) + body


def decode(body: bytes):
    try:
        return json.loads(body.decode("utf-8"), object_hook=_from_json)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise FrameError(f"a malformed frame: not UTF-8 JSON ({exc})") from exc


def _read_exactly(sock: socket.socket, n: int) -> bytes:
    buf = bytearray()
    while len(buf) < n:
        part = sock.recv(min(n - len(buf), 1 << 20))
        if not part:
            if not buf and n == HEADER.size:
                raise PeerClosed("the connection closed")
            raise FrameError(f"the connection closed after {len(buf)} of {n} bytes")
        buf += part
    return bytes(buf)


def read_frame(sock: socket.socket, max_bytes: int = DEFAULT_MAX_BYTES):
    """Read one message. Timeouts surface as `TimeoutError` (the socket's own timeout)."""
    (length,) = HEADER.unpack(_read_exactly(sock, HEADER.size))
    if length > max_bytes:
        raise FrameError(f"a length prefix of {length} bytes, over the limit of {max_bytes}")
    return decode(_read_exactly(sock, length))


def write_frame(sock: socket.socket, message: dict, max_bytes: int = DEFAULT_MAX_BYTES) -> None:
    frame = encode(message)
    if len(frame) - HEADER.size > max_bytes:
        raise FrameError(f"a message of {len(frame) - HEADER.size} bytes, over the limit of {max_bytes}")
    sock.sendall(frame)
