"""One connection to a policy server per protocol, behind the same four calls (spec, reset, chunk, executed).

Every fault (refused connection, no reply within the timeout, a malformed or oversized frame, an error
reply, a dropped connection) raises `RemoteFault` with a short description and drops the connection; the
next `reset` connects again, so one bad episode does not doom the next.
"""

from __future__ import annotations

import socket
from urllib.parse import urlsplit

from policies.remote import tcp_wire, ws_wire

DEFAULT_TIMEOUT_S = 30.0
SCHEMES = ("tcp", "ws", "wss")


class RemoteFault(Exception):
    """The server is down, slow, or broke the protocol."""


def parse_url(url: str) -> tuple[str, str, int]:
    parts = urlsplit(url)
    if parts.scheme not in SCHEMES:
        raise ValueError(f"remote policy URL '{url}': expected a scheme of {', '.join(s + '://' for s in SCHEMES)}")
    if not parts.hostname or parts.port is None:
        raise ValueError(f"remote policy URL '{url}': expected <scheme>://<host>:<port>")
    return parts.scheme, parts.hostname, parts.port


class TcpTransport:
    """The official harness's protocol (policies/remote/tcp_wire.py)."""

    def __init__(self, host: str, port: int, timeout: float = DEFAULT_TIMEOUT_S,
                 max_bytes: int = tcp_wire.DEFAULT_MAX_BYTES):
        self.host, self.port, self.timeout, self.max_bytes = host, port, timeout, max_bytes
        self.sock: socket.socket | None = None

    def _connect(self) -> socket.socket:
        if self.sock is None:
            try:
                self.sock = socket.create_connection((self.host, self.port), timeout=self.timeout)
            except OSError as exc:
                raise RemoteFault(f"cannot connect ({exc.strerror or exc})") from exc
        return self.sock

    def _call(self, message: dict):
        sock = self._connect()
        try:
            tcp_wire.write_frame(sock, message, self.max_bytes)
            reply = tcp_wire.read_frame(sock, self.max_bytes)
        except TimeoutError as exc:
            self.close(polite=False)
            raise RemoteFault(f"no reply to '{message['command']}' within {self.timeout:g} s") from exc
        except tcp_wire.FrameError as exc:
            self.close(polite=False)
            raise RemoteFault(f"replied to '{message['command']}' with {exc}") from exc
        except OSError as exc:
            self.close(polite=False)
            raise RemoteFault(f"connection failed during '{message['command']}' ({exc})") from exc
        if not isinstance(reply, dict) or not ({"result", "error"} & reply.keys()):
            self.close(polite=False)
            raise RemoteFault(f"replied to '{message['command']}' with a malformed frame: expected "
                              f"{{'result': ...}} or {{'error': ...}}, got {str(reply)[:80]}")
        if "error" in reply:              # the server may hang up after an error: start the next call afresh
            self.close(polite=False)
            raise RemoteFault(f"replied to '{message['command']}' with the error: {reply['error']}")
        return reply["result"]

    def spec(self):
        return self._call({"command": "get_spec"})

    def reset(self, seed: int, instruction: str) -> None:
        self._call({"command": "reset", "seed": int(seed), "instruction": instruction})

    def chunk(self, observation: dict, instruction: str):
        result = self._call({"command": "get_action_chunk", "observation": observation, "instruction": instruction})
        return result.get("actions") if isinstance(result, dict) else result

    def executed(self, rows: int) -> None:
        self._call({"command": "update_after_action", "executed": int(rows)})

    def close(self, polite: bool = True) -> None:
        if self.sock is None:
            return
        if polite:
            try:
                tcp_wire.write_frame(self.sock, {"command": "close"}, self.max_bytes)
            except OSError:
                pass
        self.sock.close()
        self.sock = None


class WebsocketTransport:
    """openpi's websocket protocol (policies/remote/ws_wire.py). openpi has no reset message: a b2d server
    announces `reset` in its metadata and then gets one (the seed of a sampling policy); for any other
    server a reset only reconnects when the connection was lost."""

    def __init__(self, url: str, timeout: float = DEFAULT_TIMEOUT_S, max_bytes: int = tcp_wire.DEFAULT_MAX_BYTES):
        self.url, self.timeout, self.max_bytes = url, timeout, max_bytes
        self.conn = None
        self.metadata: dict = {}

    def _connect(self):
        if self.conn is None:
            import websockets.sync.client
            from websockets.exceptions import InvalidHandshake, InvalidURI
            try:
                conn = websockets.sync.client.connect(self.url, open_timeout=self.timeout, close_timeout=1,
                                                      max_size=self.max_bytes, compression=None, legacy=True)
            except (OSError, InvalidHandshake, InvalidURI, TimeoutError) as exc:
                raise RemoteFault(f"cannot connect ({getattr(exc, 'strerror', None) or exc})") from exc
            self.conn = conn
            metadata = self._receive("the metadata")
            self.metadata = metadata if isinstance(metadata, dict) else {}
        return self.conn

    def _receive(self, what: str):
        from websockets.exceptions import ConnectionClosed
        try:
            raw = self.conn.recv(timeout=self.timeout)
        except TimeoutError as exc:
            self.close()
            raise RemoteFault(f"no reply ({what}) within {self.timeout:g} s") from exc
        except ConnectionClosed as exc:
            self.close()
            if exc.rcvd is not None and exc.rcvd.code == 1009:      # the server refused our message
                raise RemoteFault(f"refused a message from us over its size limit ({exc})") from exc
            if exc.sent is not None and exc.sent.code == 1009:      # we refused an oversized message
                raise RemoteFault(f"sent {what} in a message over the limit of {self.max_bytes} bytes") from exc
            raise RemoteFault(f"closed the connection instead of sending {what} ({exc})") from exc
        if isinstance(raw, str):          # openpi servers send an error (a traceback) as text, then close
            self.close()
            raise RemoteFault(f"replied with the error: {raw.strip().splitlines()[-1] if raw.strip() else raw}")
        try:
            return ws_wire.unpackb(raw)
        except Exception as exc:          # msgpack raises several unrelated types for bad bytes
            self.close()
            raise RemoteFault(f"sent {what} as a malformed frame: not msgpack-numpy "
                              f"({type(exc).__name__}: {exc})") from exc

    def _send(self, message: dict, what: str) -> None:
        from websockets.exceptions import ConnectionClosed
        conn = self._connect()
        try:
            conn.send(ws_wire.packb(message))
        except (ConnectionClosed, OSError) as exc:
            self.close()
            raise RemoteFault(f"connection failed sending {what} ({exc})") from exc

    def spec(self):
        self._connect()
        return self.metadata.get("b2d")

    def reset(self, seed: int, instruction: str) -> None:
        self._connect()
        if "reset" in (self.metadata.get("b2d_commands") or ()):
            self._send({"reset": {"seed": int(seed), "instruction": instruction}}, "reset")
            self._receive("the reply to reset")

    def chunk(self, observation: dict, instruction: str):
        self._send({**observation, "prompt": instruction}, "an observation")
        reply = self._receive("an action chunk")
        return reply.get("actions") if isinstance(reply, dict) else reply

    def executed(self, rows: int) -> None:
        pass                              # openpi's protocol has no such message

    def close(self) -> None:
        if self.conn is not None:
            self.conn.close()
            self.conn = None


def open_transport(url: str, timeout: float = DEFAULT_TIMEOUT_S, max_bytes: int = tcp_wire.DEFAULT_MAX_BYTES):
    scheme, host, port = parse_url(url)
    if scheme == "tcp":
        return TcpTransport(host, port, timeout, max_bytes)
    return WebsocketTransport(url, timeout, max_bytes)
