"""ARKit wrist-pose stream over the network: a UDP receiver of small JSON packets.

An iPhone app (ARKit) sends one datagram per tracking frame::

    {"t_ns": 1712345678901234567,
     "right": {"pos": [x, y, z], "quat_wxyz": [w, x, y, z]},
     "left":  {"pos": [...], "quat_wxyz": [...], "tracked": true}}

positions in metres, quaternions w-first (ARKit's simd_quatf is x-y-z-w: the sender reorders),
either hand optional, ``tracked`` defaults to true. The pose is that of the device on the wrist;
``device_to_wrist`` (the fixed device -> wrist-frame transform of the strap, per side) turns it
into the wrist-frame pose the stream carries. ARKit's world frame (y up) needs no conversion: the
arm follows wrist motion relative to the anchor taken at reset.

The socket binds to 127.0.0.1 by default; pass ``host="0.0.0.0"`` (or an interface address) to
accept a phone on the network. Malformed packets never stop the session: they are counted in
``rejected`` and the last reason is kept in ``last_error``.
"""

from __future__ import annotations

import json
import logging
import math
import socket

import numpy as np

from sim.embodiment.description import Transform, mat_to_quat, quat_to_mat

from .frame import SIDES, OperatorFrame

log = logging.getLogger(__name__)
MAX_DATAGRAM = 65507
MAX_PACKETS_PER_POLL = 1000


class PacketError(ValueError):
    """A datagram that is not a valid ARKit wrist packet."""


def _numbers(value, n: int, field: str) -> np.ndarray:
    if not isinstance(value, list) or len(value) != n or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):   # JSON true is no number
        raise PacketError(f"field '{field}': expected a list of {n} numbers, got {_short(value)}")
    try:
        return np.asarray(value, float)
    except OverflowError:       # an integer beyond float range (1e400 as a float literal reads as inf)
        raise PacketError(f"field '{field}': expected numbers within float range, got {_short(value)}") from None


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def parse_packet(payload: bytes) -> tuple[int, dict[str, tuple[np.ndarray, np.ndarray, bool]]]:
    """Datagram -> (t_ns, {side: (pos, quat_wxyz, tracked)}). Non-finite numbers are passed on
    (the sanitizer flags them); anything structurally wrong raises PacketError."""
    try:
        data = json.loads(payload.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        # ValueError: JSON syntax, or an integer of more than 4300 digits; RecursionError: deep nesting
        raise PacketError(f"not UTF-8 JSON: {type(exc).__name__}: {str(exc)[:80]}") from None
    if not isinstance(data, dict):
        raise PacketError(f"expected a JSON object, got {type(data).__name__}")
    t_ns = data.get("t_ns")
    if not isinstance(t_ns, int) or isinstance(t_ns, bool) or not 0 <= t_ns < 2**63:
        raise PacketError(f"field 't_ns': expected an integer timestamp in nanoseconds (0 to 2^63-1), "
                          f"got {_short(t_ns)}")
    hands = {}
    for side in SIDES:
        if side not in data:
            continue
        h = data[side]
        if not isinstance(h, dict):
            raise PacketError(f"field '{side}': expected an object with 'pos' and 'quat_wxyz', got {_short(h)}")
        tracked = h.get("tracked", True)
        if not isinstance(tracked, bool):
            raise PacketError(f"field '{side}.tracked': expected true or false, got {_short(tracked)}")
        hands[side] = (_numbers(h.get("pos"), 3, f"{side}.pos"), _numbers(h.get("quat_wxyz"), 4, f"{side}.quat_wxyz"),
                       tracked)
    if not hands:
        raise PacketError(f"expected at least one of the fields {list(SIDES)}")
    return t_ns, hands


class ArkitWristReceiver:
    """Non-blocking UDP receiver; ``poll()`` drains the socket and returns the newest frame."""

    def __init__(self, host: str = "127.0.0.1", port: int = 0,
                 device_to_wrist: dict[str, Transform] | None = None):
        self.device_to_wrist = device_to_wrist or {}
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind((host, port))
        self.sock.setblocking(False)
        self.received = 0
        self.rejected = 0
        self.last_error: str | None = None

    @property
    def address(self) -> tuple[str, int]:
        return self.sock.getsockname()

    def close(self) -> None:
        self.sock.close()

    def __enter__(self) -> "ArkitWristReceiver":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _frame(self, t_ns: int, hands: dict) -> OperatorFrame:
        frame = OperatorFrame.empty(t_ns)
        for side, (pos, quat, tracked) in hands.items():
            if not tracked:
                continue
            extra = self.device_to_wrist.get(side)
            n = float(np.linalg.norm(quat))
            if extra is not None and math.isfinite(n) and n > 0 and np.all(np.isfinite(pos)):
                T = Transform(pos, quat_to_mat(quat / n)) @ extra
                pos, quat = T.pos, mat_to_quat(T.rot)
            frame = frame.with_hand(side, wrist_pos=pos, wrist_quat=quat)
        return frame

    def poll(self) -> OperatorFrame | None:
        newest = None
        for _ in range(MAX_PACKETS_PER_POLL):
            try:
                payload = self.sock.recv(MAX_DATAGRAM)
            except BlockingIOError:
                break
            self.received += 1
            try:
                t_ns, hands = parse_packet(payload)
            except PacketError as exc:
                self.rejected += 1
                self.last_error = str(exc)
                log.debug("ARKit packet rejected: %s", exc)
                continue
            # datagrams may arrive out of order: keep the newest; the sanitizer judges it against
            # what was already used
            if newest is None or t_ns > newest[0]:
                newest = (t_ns, hands)
        return None if newest is None else self._frame(*newest)
