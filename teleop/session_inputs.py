"""`b2d teleop --input` specs -> the operator stream a session reads.

    recorded:PATH.npz     a recorded stream file (keypoints and wrist poses; clocked by the session)
    arkit:PORT            ARKit wrist poses as UDP JSON packets on --host (127.0.0.1 by default)
    webcam:MODEL_PATH     MediaPipe hand keypoints from camera 0 (optional extra, see streams/webcam.py)
    manus:...             refused with an explanation: the Manus runtime is read through its SDK

Two live specs are merged as in the paper's glove + ARKit setup: keypoints from the first, wrist
poses from the second (``CombinedStream``). A blocking device (the webcam waits for each camera
frame) is read on a background thread so the control loop never waits for it.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from teleop.streams import CombinedStream, OperatorFrame, OperatorStream, RecordedStream
from teleop.streams.arkit import ArkitWristReceiver
from teleop.streams.recorded import StreamFileError

ADAPTERS = ("recorded", "arkit", "webcam", "manus")
USAGE = "recorded:PATH.npz | arkit:PORT | webcam:MODEL_PATH | manus:..."


class InputError(ValueError):
    """An --input spec that names no usable stream; the message says what was expected."""


@dataclass
class SessionInput:
    stream: OperatorStream
    name: str                            # recorded | arkit | webcam | webcam+arkit ...: the operator label
    spec: str                            # the --input text, for the recording's metadata
    recorded: RecordedStream | None      # a file: the session's clock decides which frame is due
    nominal_period_ns: int | None        # the stream's frame period, when known (sanitizer drop test)
    description: str
    closers: list[Callable[[], None]] = field(default_factory=list)

    def close(self) -> None:
        for close in reversed(self.closers):
            close()
        self.closers.clear()


class BackgroundPoller:
    """Reads a blocking stream on a daemon thread; ``poll()`` returns the newest frame not yet
    returned (or None) without waiting."""

    def __init__(self, stream: OperatorStream, name: str):
        self.stream = stream
        self._lock = threading.Lock()
        self._newest: OperatorFrame | None = None
        self._stop = threading.Event()
        self.error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name=f"b2d-{name}-reader", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                frame = self.stream.poll()
                if frame is not None:
                    with self._lock:
                        self._newest = frame
        except Exception as exc:       # surfaced by poll(): the session reports it and stops
            self.error = exc

    def poll(self) -> OperatorFrame | None:
        if self.error is not None:
            raise RuntimeError(f"input reader stopped: {self.error}") from self.error
        with self._lock:
            frame, self._newest = self._newest, None
        return frame

    def close(self, timeout_s: float = 2.0) -> None:
        self._stop.set()
        self._thread.join(timeout_s)


def _split(spec: str) -> tuple[str, str]:
    kind, sep, arg = spec.partition(":")
    kind = kind.strip().lower()
    if not sep or kind not in ADAPTERS:
        raise InputError(f"--input {spec!r}: expected one of {USAGE}")
    if not arg and kind != "manus":
        raise InputError(f"--input {spec!r}: '{kind}:' needs a value ({USAGE})")
    return kind, arg


def recorded_period_ns(stream: RecordedStream) -> int | None:
    """The file's frame period: the median of its positive timestamp steps."""
    t = np.array([f.timestamp_ns for f in stream.frames], np.int64)
    steps = np.diff(t)
    steps = steps[steps > 0]
    return int(np.median(steps)) if steps.size else None


def _open_recorded(spec: str, arg: str) -> SessionInput:
    path = Path(arg)
    if not path.is_file():
        raise InputError(f"--input {spec!r}: no recorded stream file at {path}")
    try:
        stream = RecordedStream(path)
    except StreamFileError as exc:
        raise InputError(str(exc)) from None
    if len(stream) == 0:
        raise InputError(f"{path}: field 'timestamp_ns': expected at least one frame, got none")
    return SessionInput(stream, "recorded", spec, stream, recorded_period_ns(stream),
                        f"recorded stream {path} ({len(stream)} frames)")


def _open_live(spec: str, kind: str, arg: str, host: str) -> tuple[OperatorStream, str, list]:
    if kind == "arkit":
        try:
            port = int(arg)
        except ValueError:
            raise InputError(f"--input {spec!r}: expected 'arkit:PORT' with a UDP port number") from None
        if not 0 <= port <= 65535:
            raise InputError(f"--input {spec!r}: port {port} is outside 0..65535")
        try:
            receiver = ArkitWristReceiver(host, port)
        except OSError as exc:
            raise InputError(f"--input {spec!r}: cannot listen on udp {host}:{port} ({exc})") from None
        h, p = receiver.address
        return receiver, f"ARKit wrist poses on udp {h}:{p}", [receiver.close]
    if kind == "webcam":
        from teleop.streams.webcam import WebcamHandStream, WebcamUnavailable

        try:
            camera = WebcamHandStream(arg)
        except WebcamUnavailable as exc:
            raise InputError(f"--input {spec!r}: {exc}") from None
        poller = BackgroundPoller(camera, "webcam")
        return poller, f"webcam keypoints (MediaPipe model {arg})", [camera.close, poller.close]
    assert kind == "manus"
    raise InputError(
        f"--input {spec!r}: the Manus runtime hands its 25-node skeletons out only through the Manus Core "
        f"SDK (shared memory on the operator's PC), which b2d does not include. Drive a session from "
        f"Python with teleop.streams.manus.ManusStream(read=<your SDK callback>), or save the glove's "
        f"frames with teleop.streams.write_stream and use --input recorded:PATH.npz")


def open_input(specs: list[str] | tuple[str, ...], host: str = "127.0.0.1",
               stream_hz: float | None = None) -> SessionInput:
    """One spec, or two live specs merged (keypoints from the first, wrist poses from the second)."""
    if not specs or len(specs) > 2:
        raise InputError(f"--input: expected one stream, or two to merge (keypoints, then wrists); got {len(specs)}")
    parsed = [_split(s) for s in specs]
    period = int(round(1e9 / stream_hz)) if stream_hz else None
    if any(kind == "recorded" for kind, _ in parsed):
        if len(specs) > 1:
            raise InputError("--input: a recorded stream carries keypoints and wrist poses already; give it alone")
        source = _open_recorded(specs[0], parsed[0][1])
        source.nominal_period_ns = period or source.nominal_period_ns
        return source
    opened = []
    try:
        for spec, (kind, arg) in zip(specs, parsed):
            opened.append((kind,) + _open_live(spec, kind, arg, host))
    except BaseException:
        for _, _, _, closers in opened:
            for close in closers:
                close()
        raise
    closers = [c for *_, cs in opened for c in cs]
    if len(opened) == 1:
        kind, stream, text, _ = opened[0]
        return SessionInput(stream, kind, specs[0], None, period, text, closers)
    (k1, s1, t1, _), (k2, s2, t2, _) = opened
    return SessionInput(CombinedStream(s1, s2), f"{k1}+{k2}", " + ".join(specs), None, period,
                        f"keypoints: {t1}; wrist poses: {t2}", closers)
