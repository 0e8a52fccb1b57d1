"""Tiny misbehaving policy servers on real sockets (127.0.0.1, ephemeral ports), one per fault, and a real
policy with a declared spec that needs no rendering (no views), for the fault tests."""

from __future__ import annotations

import socket
import threading

import numpy as np

from policies.interface import ActionSpec, ObservationSpec
from policies.remote import tcp_wire, ws_wire
from policies.remote.spec import RemoteSpec

FAULTS = ("slow", "malformed", "oversized", "wrong_shape", "error")


def glance_spec(scene, name: str = "glance") -> RemoteSpec:
    """A policy that reads the joints and one tiny view, for the scene's embodiment."""
    model = scene.model
    obs = ObservationSpec(views=(model.camera(0).name,), width=16, height=12, rate_hz=20,
                          state_names=tuple(scene.layout.joint_names))
    return RemoteSpec(name, obs, ActionSpec(tuple(model.actuator(i).name for i in range(model.nu))), 1)


class HoldStill:
    """A real (trivial) policy for that spec: the actuators' zero targets."""

    def __init__(self, spec: RemoteSpec):
        self.name, self.observation_spec, self.action_spec = spec.name, spec.observation_spec, spec.action_spec
        self.actions_per_query = 1

    def reset(self, seed, instruction):
        pass

    def act(self, observation):
        return np.zeros((1, self.action_spec.dim))


def closed_port() -> int:
    """A port nothing listens on (bound, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def fault_tcp_reply(fault: str, sock: socket.socket, stop: threading.Event) -> None:
    if fault == "slow":
        stop.wait(10)
    elif fault == "malformed":
        sock.sendall(tcp_wire.HEADER.pack(9) + b"not json!")
    elif fault == "oversized":
        sock.sendall(tcp_wire.HEADER.pack(2**31))
    elif fault == "wrong_shape":
        sock.sendall(tcp_wire.encode({"result": np.zeros((1, 3))}))
    elif fault == "error":
        sock.sendall(tcp_wire.encode({"error": "model exploded"}))
    else:
        raise AssertionError(fault)


def fault_ws_reply(fault: str, conn, stop: threading.Event) -> None:
    if fault == "slow":
        stop.wait(10)
    elif fault == "malformed":
        conn.send(b"\xc1\xc1\xc1")                      # 0xc1 is never used by msgpack
    elif fault == "oversized":
        conn.send(ws_wire.packb({"actions": np.zeros((64, 64))}))
    elif fault == "wrong_shape":
        conn.send(ws_wire.packb({"actions": np.zeros((1, 3))}))
    elif fault == "error":
        conn.send("Traceback (most recent call last):\nRuntimeError: model exploded")
        conn.close(1011, "internal server error")
    else:
        raise AssertionError(fault)


class FaultyServer:
    """Answers like a harness (tcp) or openpi (ws) server, but with `fault` at chosen action queries
    (`faulty(query_index)`; by default every one). Good queries get zero targets of `action_dim`."""

    def __init__(self, protocol: str, fault: str, action_dim: int, faulty=lambda i: True):
        self.protocol, self.fault, self.action_dim, self.faulty = protocol, fault, action_dim, faulty
        self.queries = 0
        self.stop = threading.Event()
        if protocol == "tcp":
            self.listener = socket.create_server(("127.0.0.1", 0))
            self.port = self.listener.getsockname()[1]
            self.thread = threading.Thread(target=self._tcp_accept, daemon=True)
        else:
            from websockets.sync.server import serve
            self.server = serve(self._ws_session, "127.0.0.1", 0, compression=None)
            self.port = self.server.socket.getsockname()[1]
            self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)
        self.thread.start()

    @property
    def url(self) -> str:
        return f"{self.protocol}://127.0.0.1:{self.port}"

    def _next_is_faulty(self) -> bool:
        self.queries += 1
        return self.faulty(self.queries - 1)

    def _tcp_accept(self) -> None:
        while not self.stop.is_set():
            try:
                sock, _ = self.listener.accept()
            except OSError:
                return
            threading.Thread(target=self._tcp_session, args=(sock,), daemon=True).start()

    def _tcp_session(self, sock: socket.socket) -> None:
        with sock:
            while True:
                try:
                    message = tcp_wire.read_frame(sock)
                except (tcp_wire.FrameError, OSError):
                    return
                command = message["command"]
                if command == "close":
                    return
                if command == "get_action_chunk":
                    if self._next_is_faulty():
                        fault_tcp_reply(self.fault, sock, self.stop)
                        return
                    sock.sendall(tcp_wire.encode({"result": np.zeros((1, self.action_dim))}))
                else:
                    sock.sendall(tcp_wire.encode({"result": {}}))

    def _ws_session(self, conn) -> None:
        from websockets.exceptions import ConnectionClosed
        try:
            conn.send(ws_wire.packb({"server": "not b2d"}))
            while True:
                ws_wire.unpackb(conn.recv())
                if self._next_is_faulty():
                    fault_ws_reply(self.fault, conn, self.stop)
                    return
                conn.send(ws_wire.packb({"actions": np.zeros((1, self.action_dim))}))
        except ConnectionClosed:
            return

    def close(self) -> None:
        self.stop.set()
        if self.protocol == "tcp":
            self.listener.close()
        else:
            self.server.shutdown()
