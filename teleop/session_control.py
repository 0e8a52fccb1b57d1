"""The session's control channel: start / save / discard / home (plus status and quit) from a script,
a loopback TCP port or the keyboard.

* Script (``--script "start;wait 2.0;save"`` or a control file, one item per line, ``#`` comments):
  commands run at the control step they are reached; ``wait S`` lets S seconds of session time
  (round(S x 60) control steps) pass first, so a script drives a recorded stream reproducibly.
* TCP port (127.0.0.1 by default): one command per line; each gets one reply line, ``ok ...`` or
  ``error ...``, after it has run. The port has no authentication: keep it on loopback.
* Keyboard, when stdin is a terminal: single keys (``KEYS``), no Enter needed.

Every source is polled without blocking once per control step; its requests run before the step.
"""

from __future__ import annotations

import math
import os
import select
import selectors
import socket
import termios
import tty
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from sim import physics

COMMANDS = ("start", "save", "discard", "home", "status", "quit")
KEYS = {"s": "start", "w": "save", "d": "discard", "h": "home", "?": "status", "q": "quit"}
KEY_HELP = "  ".join(f"[{k}] {c}" for k, c in KEYS.items())
MAX_LINE = 1024


class ControlScriptError(ValueError):
    """A control script item that is not a command or ``wait SECONDS``."""


@dataclass(frozen=True)
class Request:
    command: str
    reply: Callable[[bool, str], None]     # (ok, message), called once after the command ran


@dataclass(frozen=True)
class ScriptItem:
    command: str            # one of COMMANDS, or "wait"
    wait_steps: int = 0


def parse_script(text: str, source: str = "--script", number_lines: bool = False) -> list[ScriptItem]:
    """``;`` or newline separated items; errors name the source, the item and (for files) the line."""
    items = []
    for line_no, line in enumerate(text.splitlines() or [""], 1):
        line = line.split("#", 1)[0]
        for part in line.split(";"):
            words = part.split()
            if not words:
                continue
            where = f"{source}, line {line_no}" if number_lines else source
            if words[0] == "wait":
                try:
                    seconds = float(words[1]) if len(words) == 2 else math.nan
                except ValueError:
                    seconds = math.nan
                if not (math.isfinite(seconds) and seconds >= 0):
                    raise ControlScriptError(f"{where}: item {part.strip()!r}: expected 'wait SECONDS' with a "
                                             f"number of seconds >= 0")
                items.append(ScriptItem("wait", round(seconds * physics.CONTROL_HZ)))
            elif len(words) == 1 and words[0] in COMMANDS:
                items.append(ScriptItem(words[0]))
            else:
                raise ControlScriptError(f"{where}: item {part.strip()!r}: expected one of "
                                         f"{', '.join(COMMANDS)} or 'wait SECONDS'")
    return items


def read_control_file(path: str | os.PathLike) -> list[ScriptItem]:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ControlScriptError(f"{path}: not a readable UTF-8 control file ({exc})") from None
    return parse_script(text, str(path), number_lines=True)


class ScriptControl:
    """Runs a parsed script against the session's step count; counts refused commands."""

    def __init__(self, items: list[ScriptItem], say: Callable[[str], None]):
        self.items, self.say = list(items), say
        self.next = 0
        self.resume_step = 0
        self.refused: list[str] = []

    def done(self, step: int) -> bool:
        return self.next >= len(self.items) and step >= self.resume_step

    def poll(self, step: int) -> list[Request]:
        out = []
        while self.next < len(self.items) and step >= self.resume_step:
            item = self.items[self.next]
            self.next += 1
            if item.command == "wait":
                self.resume_step = step + item.wait_steps
            else:
                out.append(Request(item.command, self._reply(item.command, step)))
        return out

    def _reply(self, command: str, step: int) -> Callable[[bool, str], None]:
        def reply(ok: bool, message: str) -> None:
            self.say(f"[script, step {step}] {command}: {message}")
            if not ok:
                self.refused.append(f"{command} at step {step}: {message}")
        return reply


class ControlPort:
    """Line-based TCP control on ``host:port`` (0 = any free port; see ``address``)."""

    def __init__(self, host: str = "127.0.0.1", port: int = 0):
        self.server = socket.create_server((host, port))
        self.server.setblocking(False)
        self.selector = selectors.DefaultSelector()
        self.selector.register(self.server, selectors.EVENT_READ)
        self.pending: dict[socket.socket, bytes] = {}

    @property
    def address(self) -> tuple[str, int]:
        return self.server.getsockname()[:2]

    def _drop(self, conn: socket.socket) -> None:
        self.selector.unregister(conn)
        self.pending.pop(conn, None)
        conn.close()

    @staticmethod
    def _send(conn: socket.socket, ok: bool, message: str) -> None:
        try:
            conn.sendall(f"{'ok' if ok else 'error'} {message}\n".encode())
        except OSError:
            pass        # the client left; nothing to tell

    def poll(self, step: int) -> list[Request]:
        out = []
        for key, _ in self.selector.select(timeout=0):
            sock = key.fileobj
            if sock is self.server:
                try:
                    conn, _ = self.server.accept()
                except BlockingIOError:
                    continue
                conn.setblocking(False)
                self.selector.register(conn, selectors.EVENT_READ)
                self.pending[conn] = b""
                continue
            try:
                data = sock.recv(4096)
            except (BlockingIOError, InterruptedError):
                continue
            except OSError:
                data = b""
            if not data:
                self._drop(sock)
                continue
            buffer = self.pending[sock] + data
            *lines, rest = buffer.split(b"\n")
            if len(rest) > MAX_LINE:
                self._send(sock, False, f"line longer than {MAX_LINE} bytes; closing")
                self._drop(sock)
                continue
            self.pending[sock] = rest
            for raw in lines:
                text = raw.decode("utf-8", "replace").strip().lower()
                if not text:
                    continue
                if text in COMMANDS:
                    out.append(Request(text, lambda ok, msg, c=sock: self._send(c, ok, msg)))
                else:
                    self._send(sock, False, f"unknown command {text!r}; expected one of {', '.join(COMMANDS)}")
        return out

    def close(self) -> None:
        for conn in list(self.pending):
            self._drop(conn)
        self.selector.unregister(self.server)
        self.server.close()
        self.selector.close()


class KeyboardControl:
    """Single keys from a terminal (``KEYS``); the terminal is put in cbreak mode until ``close``."""

    def __init__(self, fd: int, say: Callable[[str], None]):
        self.fd, self.say = fd, say
        self._saved = termios.tcgetattr(fd)
        tty.setcbreak(fd)

    def poll(self, step: int) -> list[Request]:
        out = []
        while select.select([self.fd], [], [], 0)[0]:
            data = os.read(self.fd, 64)
            if not data:
                break
            for key in data.decode("utf-8", "replace"):
                if key in KEYS:
                    command = KEYS[key]
                    out.append(Request(command, lambda ok, msg, c=command: self.say(f"{c}: {msg}")))
                elif not key.isspace():
                    self.say(f"key {key!r} does nothing; keys: {KEY_HELP}")
        return out

    def close(self) -> None:
        termios.tcsetattr(self.fd, termios.TCSADRAIN, self._saved)
