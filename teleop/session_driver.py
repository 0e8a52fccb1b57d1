"""Operator stream -> one joint command per control step: the latest frame due, sanitized, retargeted.

The session's clock is its control-step count (60 Hz), so a recorded stream plays back the same
way in real time and as fast as possible: at session time ``now`` the file's frames stamped up to
``first frame + now`` are due and the newest of them is used (a faster stream skips frames, a
slower one leaves steps without a new frame). A live device delivers its newest frame itself; its
clock is related to the session's by the arrival time of its newest frame, so the sanitizer can
tell a slow stream from a lost frame.

``StreamOperator`` wraps the driver in the recorder's ``Operator`` protocol (flags included), so
``record_episode`` records a stream exactly as the scripted operator's demonstrations. Each step's
input (``last_step``: the frame polled, or None, and the stream-clock time) is what the recorder
keeps as the recording's operator stream; ``command_for`` runs the same sanitizer and commander on
such an input, which is how `b2d retarget` (``teleop/retarget_demo.py``) replays a recorded one.
"""

from __future__ import annotations

import mujoco
import numpy as np

from sim import physics
from sim.scene.builder import Scene
from teleop.recorder import StreamStep, stream_settings
from teleop.retarget import Command, DexPilotConfig, TeleopCommander
from teleop.streams import OperatorFrame, StreamSanitizer

from .session_inputs import SessionInput

NS_PER_S = 1_000_000_000


def session_time_ns(step: int) -> int:
    """Start of control step ``step`` on the session clock (integer ns, no drift)."""
    return step * NS_PER_S // physics.CONTROL_HZ


class StreamDriver:
    def __init__(self, source: SessionInput, translation_scale: float = 1.0,
                 retarget_config: DexPilotConfig = DexPilotConfig()):
        self.source = source
        self.translation_scale = translation_scale
        self.retarget_config = retarget_config
        self.last_step: StreamStep | None = None
        self.sanitizer = StreamSanitizer(source.nominal_period_ns)
        self.commander: TeleopCommander | None = None
        self._model: mujoco.MjModel | None = None
        self._t0 = source.recorded.frames[0].timestamp_ns if source.recorded else None
        self._offset: int | None = None       # device clock - session clock, at the newest arrival
        self._newest: int | None = None

    def attach(self, scene: Scene) -> None:
        """Command this scene's robot (a new commander only when the model changed)."""
        if scene.model is not self._model:
            self.commander = TeleopCommander(scene.model, scene.layout, self.translation_scale, self.retarget_config)
            self._model = scene.model

    def reset(self) -> np.ndarray:
        """Home command; filters, wrist anchors and the held stream values forgotten."""
        self.sanitizer.reset()
        return self.commander.reset()

    def command(self, now_ns: int) -> Command:
        rec = self.source.recorded
        if rec is not None:
            stream_now = self._t0 + now_ns
            frame = rec.poll(stream_now)
        else:
            frame = self.source.stream.poll()
            if frame is not None and (self._newest is None or frame.timestamp_ns >= self._newest):
                self._newest, self._offset = frame.timestamp_ns, frame.timestamp_ns - now_ns
            stream_now = None if self._offset is None else now_ns + self._offset
        return self.command_for(frame, stream_now)

    def command_for(self, frame: OperatorFrame | None, stream_now_ns: int | None) -> Command:
        """One step's input (the frame polled, or None; the time on the stream's clock) -> command."""
        self.last_step = StreamStep(frame, stream_now_ns)
        return self.commander.command(self.sanitizer.step(frame, stream_now_ns))

    @property
    def stream_settings(self) -> dict:
        return stream_settings(self.sanitizer.nominal_period_ns, self.translation_scale, self.retarget_config)


class StreamOperator:
    """The recorder's Operator over a stream: ``act`` polls at the episode step's time; the step's
    ``StepFlag`` bits and reasons are left in ``step_flags`` / ``step_reasons``."""

    def __init__(self, source: SessionInput, translation_scale: float = 1.0):
        self.driver = StreamDriver(source, translation_scale)
        self.name = f"teleop:{source.name}"
        self.step_flags, self.step_reasons = 0, ""
        self.stream_settings = self.driver.stream_settings

    @property
    def stream_step(self) -> StreamStep | None:
        return self.driver.last_step

    def reset(self, scene: Scene, data: mujoco.MjData) -> None:
        self.driver.attach(scene)
        self.driver.reset()

    def act(self, step: int, data: mujoco.MjData) -> np.ndarray:
        cmd = self.driver.command(session_time_ns(step))
        self.step_flags, self.step_reasons = int(cmd.flags), "\n".join(cmd.reasons)
        return cmd.ctrl

    def done(self, step: int) -> bool:
        rec = self.driver.source.recorded
        return rec is not None and rec.done()
