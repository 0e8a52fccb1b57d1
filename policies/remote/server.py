"""Serve any policy (a b2d checkpoint through `LearnedPolicy`) over either protocol, so that both are tested
end to end here and a b2d policy can stand in for a pi0.5 or GR00T server.

The server binds 127.0.0.1 unless told otherwise and refuses messages over its size limit (TCP: an error
reply, then it hangs up, since the stream cannot be trusted after a refused frame; websocket: close code
1009). Connections are served on their own threads, but the policy is one object with one episode state,
behind a lock, as in openpi's server: evaluate one client at a time.
"""

from __future__ import annotations

import logging
import socket
import socketserver
import threading

from policies.interface import Policy
from policies.remote import tcp_wire, ws_wire
from policies.remote.layout import Layout, check_layout_fits
from policies.remote.spec import checkpoint_spec

log = logging.getLogger(__name__)
PROTOCOLS = ("tcp", "ws")
COMMANDS = ("get_spec", "reset", "get_action_chunk", "update_after_action", "close")


class PolicyService:
    """The protocol-free part: one policy, its spec, a lock, and the fixed-width layout on the wire if any
    (states arrive encoded and are decoded for the policy; its actions leave encoded)."""

    def __init__(self, policy: Policy, layout: Layout | None = None):
        self.policy, self.layout = policy, layout
        spec = checkpoint_spec(policy, layout.to_dict() if layout is not None else None)
        if layout is not None:
            check_layout_fits(layout, spec, f"layout for {policy.name}")
        self.spec = spec.to_dict()
        self.lock = threading.Lock()

    def reset(self, seed: int, instruction: str) -> None:
        with self.lock:
            self.policy.reset(int(seed), str(instruction))

    def act(self, observation: dict):
        if self.layout is not None and "state" in observation:
            observation = {**observation, "state": self.layout.state.decode(observation["state"])}
        with self.lock:
            chunk = self.policy.act(observation)
        return self.layout.action.encode(chunk) if self.layout is not None else chunk


class _TcpHandler(socketserver.BaseRequestHandler):
    def handle(self) -> None:
        server: TcpPolicyServer = self.server
        sock: socket.socket = self.request
        sock.settimeout(server.idle_timeout)
        while True:
            try:
                message = tcp_wire.read_frame(sock, server.max_bytes)
            except tcp_wire.PeerClosed:
                return
            except tcp_wire.FrameError as exc:
                log.warning("refused a frame from %s: %s", self.client_address, exc)
                self._reply({"error": f"refused {exc}"})
                return
            except OSError:
                return
            reply = self._dispatch(server.service, message)
            if reply is None:
                return
            self._reply(reply)

    def _reply(self, reply: dict) -> None:
        try:
            tcp_wire.write_frame(self.request, reply, self.server.max_bytes)
        except (OSError, tcp_wire.FrameError) as exc:
            log.warning("could not reply to %s: %s", self.client_address, exc)

    @staticmethod
    def _dispatch(service: PolicyService, message) -> dict | None:
        if not isinstance(message, dict) or message.get("command") not in COMMANDS:
            got = message.get("command") if isinstance(message, dict) else type(message).__name__
            return {"error": f"unknown command {got!r}; expected one of {', '.join(COMMANDS)}"}
        command = message["command"]
        try:
            if command == "close":
                return None
            if command == "get_spec":
                return {"result": service.spec}
            if command == "reset":
                service.reset(message["seed"], message.get("instruction", ""))
                return {"result": {}}
            if command == "update_after_action":
                return {"result": {}}                  # b2d policies keep their own queue; nothing to update
            observation = dict(message["observation"])
            return {"result": service.act(observation)}
        except Exception as exc:                       # the policy's fault: tell the client, keep serving
            log.exception("%s failed", command)
            return {"error": f"{command}: {type(exc).__name__}: {exc}"}


class TcpPolicyServer(socketserver.ThreadingTCPServer):
    allow_reuse_address = True
    daemon_threads = True

    def __init__(self, service: PolicyService, host: str, port: int, max_bytes: int, idle_timeout: float):
        self.service, self.max_bytes, self.idle_timeout = service, max_bytes, idle_timeout
        super().__init__((host, port), _TcpHandler)

    @property
    def address(self) -> tuple[str, int]:
        return self.server_address[:2]

    def serve_forever(self, poll_interval: float = 0.5) -> None:
        self.serving = True
        super().serve_forever(poll_interval)

    def close(self) -> None:
        if getattr(self, "serving", False):   # shutdown() waits for a serve_forever loop: never started, it hangs
            self.shutdown()
        self.server_close()


class WebsocketPolicyServer:
    """openpi's session: metadata on connect, then observation in, {"actions": chunk} out; `reset` (announced
    in the metadata) carries the episode's seed."""

    def __init__(self, service: PolicyService, host: str, port: int, max_bytes: int, idle_timeout: float):
        from websockets.sync.server import serve

        self.service, self.idle_timeout = service, idle_timeout
        self.metadata = {"b2d": service.spec, "b2d_commands": ["reset"]}
        self.server = serve(self._session, host, port, max_size=max_bytes, compression=None)

    @property
    def address(self) -> tuple[str, int]:
        return self.server.socket.getsockname()[:2]

    def _session(self, conn) -> None:
        from websockets.exceptions import ConnectionClosed

        try:
            conn.send(ws_wire.packb(self.metadata))
            while True:
                raw = conn.recv(timeout=self.idle_timeout)
                try:
                    message = ws_wire.unpackb(raw) if isinstance(raw, bytes) else None
                    if not isinstance(message, dict):
                        raise ValueError("expected a msgpack-numpy mapping")
                    if "reset" in message:
                        self.service.reset(message["reset"]["seed"], message["reset"].get("instruction", ""))
                        conn.send(ws_wire.packb({"reset": True}))
                        continue
                    message.setdefault("instruction", message.get("prompt", ""))
                    conn.send(ws_wire.packb({"actions": self.service.act(message)}))
                except Exception as exc:               # as openpi: the error as text, then close (1011)
                    log.exception("websocket request failed")
                    conn.send(f"{type(exc).__name__}: {exc}")
                    conn.close(1011, "internal server error")
                    return
        except (ConnectionClosed, TimeoutError):
            return

    def serve_forever(self) -> None:
        self.server.serve_forever()

    def close(self) -> None:
        self.server.shutdown()


def make_server(policy: Policy, protocol: str = "tcp", host: str = "127.0.0.1", port: int = 0,
                max_bytes: int = tcp_wire.DEFAULT_MAX_BYTES, idle_timeout: float = 600.0,
                layout: Layout | None = None):
    """A bound server (port 0: an ephemeral port; read `.address`). Call `serve_forever()`; `close()` stops it."""
    if protocol not in PROTOCOLS:
        raise ValueError(f"protocol '{protocol}': expected one of {', '.join(PROTOCOLS)}")
    cls = TcpPolicyServer if protocol == "tcp" else WebsocketPolicyServer
    return cls(PolicyService(policy, layout), host, port, max_bytes, idle_timeout)


def server_url(protocol: str, address: tuple[str, int]) -> str:
    return f"{protocol}://{address[0]}:{address[1]}"
