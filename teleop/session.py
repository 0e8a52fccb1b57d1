"""A live teleoperation session (`b2d teleop`): a person (or a script) drives the robot through an
operator stream and keeps the episodes worth keeping.

Each 60 Hz control step: the latest frame of the stream is sanitized and turned into one absolute
joint command (``session_driver.py``), physics steps, and while an episode is open the online
recorder stores the step with the stream's flags and reasons. Between episodes the robot still
follows the operator (a rehearsal, not recorded). Controls (``session_control.py``):

* ``start``: home (paper: the robot goes home, the filters and wrist anchors reset), then record;
* ``save``: write the raw recording (atomically, the format of `b2d record`, operator
  ``teleop:<adapter>``), then the next episode's scene, homed;
* ``discard``: drop the episode and home in the same scene (a retry of the same sample);
* ``home``: home without recording; ``status``; ``quit`` (an open episode is discarded).

Episode i lives in the scene sample of seed ``task_seed(task, i)``, as `b2d record`'s episode i;
the first index is the first one with no file in the output folder. The evaluator decides success;
recording stops by itself at stable success (reach-and-stop, as `b2d record`) or at the horizon,
and waits for save or discard. Pacing: wall-clock rate by default (a step that overruns is counted
and the schedule resynchronised rather than raced to catch up); ``realtime=False`` runs as fast as
possible, for recorded streams. With a recorded stream and a script the session is reproducible:
the stream and the script both follow the control-step count, not the wall clock.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from episodes.raw import write_raw
from sim import physics
from sim.registry import names, validate_name
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample, task_seed
from sim.tasks import load_task
from teleop.demos import raw_filename
from teleop.recorder import EpisodeRecording, episode_horizon, home
from teleop.streams import StepFlag

from .session_driver import StreamDriver, session_time_ns
from .session_inputs import SessionInput

log = logging.getLogger(__name__)
FLAG_BITS = {name: int(flag) for name, flag in StepFlag.__members__.items() if flag}


@dataclass(frozen=True)
class SavedEpisode:
    episode_id: str
    path: Path
    steps: int
    success: bool
    flagged_steps: int


class Pacer:
    """Holds the loop to one control period per step on the wall clock (when enabled)."""

    def __init__(self, enabled: bool, period_s: float = physics.CONTROL_DT, clock=time.perf_counter):
        self.enabled, self.period_s, self.clock = enabled, period_s, clock
        self.late_steps = 0
        self.resync()

    def resync(self) -> None:
        self.next = self.clock()

    def wait(self) -> None:
        if not self.enabled:
            return
        self.next += self.period_s
        delay = self.next - self.clock()
        if delay > 0:
            time.sleep(delay)
        else:              # behind: count it and start the schedule afresh instead of racing
            self.late_steps += 1
            self.next = self.clock()


class TeleopSession:
    def __init__(self, task: str, embodiment: str, source: SessionInput, out_dir: str | Path, *,
                 first_index: int = 0, max_steps: int | None = None, stop_on_success: bool = True,
                 translation_scale: float = 1.0, say: Callable[[str], None] = log.info):
        self.task, self.embodiment = validate_name("task", task), validate_name("embodiment", embodiment)
        self.spec = load_task(task)
        self.task_index = names("tasks").index(task)
        self.source, self.out_dir, self.say = source, Path(out_dir), say
        self.max_steps, self.stop_on_success = max_steps, stop_on_success
        self.translation_scale = translation_scale
        self.driver = StreamDriver(source, translation_scale)
        self.step_count = 0                    # session control steps (the session clock)
        self.episode: EpisodeRecording | None = None
        self.recording = False                 # the open episode still takes steps
        self.ended_by: str | None = None       # why recording stopped by itself
        self.saved: list[SavedEpisode] = []
        self.quit_requested = False
        self.homed = False                     # set by homing: the pacer resynchronises
        self.index = self._free_index(first_index)
        self._load_scene()

    # ------------------------------------------------------------------ episodes and scenes
    @property
    def episode_id(self) -> str:
        return f"{self.index:04d}"

    @property
    def seed(self) -> int:
        return task_seed(self.task_index, self.index)

    def _free_index(self, index: int) -> int:
        while (self.out_dir / raw_filename(f"{index:04d}")).exists():
            index += 1
        return index

    def _load_scene(self) -> None:
        self.scene = build_scene(self.spec, self.embodiment, demonstration_sample(self.spec, self.seed))
        self.horizon = episode_horizon(self.scene, self.max_steps)
        self.driver.attach(self.scene)
        self._home()

    def _home(self) -> None:
        self.data = home(self.scene)
        self.driver.reset()
        self.homed = True

    # ------------------------------------------------------------------ controls
    def handle(self, command: str) -> tuple[bool, str]:
        """Run one control command; returns (accepted, message)."""
        handlers = {"start": self._start, "save": self._save, "discard": self._discard, "home": self._go_home,
                    "status": lambda: (True, self.status()), "quit": self._quit}
        if command not in handlers:
            return False, f"unknown command {command!r}; expected one of {', '.join(handlers)}"
        return handlers[command]()

    def _open(self) -> str:
        return f"episode {self.episode_id} is open ({self.episode.steps} steps): save or discard it first"

    def _start(self) -> tuple[bool, str]:
        if self.episode is not None:
            return False, self._open()
        self._home()
        self.episode = EpisodeRecording(self.scene, self.data, stream_settings=self.driver.stream_settings)
        self.recording, self.ended_by = True, None
        self._latched = np.zeros(len(self.episode.evaluator.stage_ids), bool)
        return True, f"home; recording episode {self.episode_id} (seed {self.seed})"

    def _save(self) -> tuple[bool, str]:
        if self.episode is None:
            return False, "no episode to save: start one first"
        if self.episode.steps == 0:
            return False, f"episode {self.episode_id} has no steps yet"
        termination = "stable_success" if self.episode.evaluator.stable else (self.ended_by or "saved")
        rec = self.episode.finish(self.episode_id, self.seed, f"teleop:{self.source.name}", termination,
                                  extra={"input": self.source.spec, "step_flag_bits": FLAG_BITS,
                                         "translation_scale": self.translation_scale})
        try:
            path = write_raw(self.out_dir / raw_filename(self.episode_id), rec)
        except OSError as exc:        # the episode stays open: free some space and save again
            return False, f"could not write {self.out_dir / raw_filename(self.episode_id)}: {exc}"
        flagged = int(np.count_nonzero(rec.step_flags))
        self.saved.append(SavedEpisode(self.episode_id, path, rec.num_steps, rec.success, flagged))
        self.episode = None
        self.index = self._free_index(self.index + 1)
        self._load_scene()
        return True, (f"saved {path} ({rec.num_steps} steps, {'success' if rec.success else 'no success'}, "
                      f"{flagged} flagged steps); home, next episode {self.episode_id}")

    def _discard(self) -> tuple[bool, str]:
        if self.episode is None:
            return False, "no episode to discard"
        steps, self.episode = self.episode.steps, None
        self._home()
        return True, f"discarded episode {self.episode_id} ({steps} steps); home"

    def _go_home(self) -> tuple[bool, str]:
        if self.episode is not None:
            return False, self._open()
        self._home()
        return True, "home"

    def _quit(self) -> tuple[bool, str]:
        self.quit_requested = True
        if self.episode is None:
            return True, "bye"
        steps, self.episode = self.episode.steps, None
        return True, f"episode {self.episode_id} discarded ({steps} steps, not saved); bye"

    def status(self) -> str:
        t = f"t={self.step_count * physics.CONTROL_DT:.2f}s"
        if self.episode is None:
            return (f"{t} idle (following the operator, not recording); next episode {self.episode_id}; "
                    f"saved {len(self.saved)}")
        ev = self.episode.evaluator
        state = "recording" if self.recording else f"stopped ({self.ended_by}): save or discard"
        latched = sum(ev.latched.values())
        flagged = int(np.count_nonzero(self.episode.buf.arrays["step_flags"][: self.episode.steps]))
        return (f"{t} episode {self.episode_id} {state}: {self.episode.steps} steps, "
                f"stages {latched}/{len(ev.stage_ids)}, {'stable success' if ev.stable else 'no success yet'}, "
                f"{flagged} flagged steps")

    # ------------------------------------------------------------------ the loop
    def step(self) -> None:
        """One control step: command from the stream, physics, and the recorder when recording."""
        cmd = self.driver.command(session_time_ns(self.step_count))
        physics.step_control(self.scene.model, self.data, cmd.ctrl)
        if self.episode is not None and self.recording:
            record = self.episode.step(self.data, cmd.ctrl, int(cmd.flags), "\n".join(cmd.reasons),
                                       stream=self.driver.last_step)
            for k in np.flatnonzero(record.stage_latched & ~self._latched):
                self.say(f"stage '{self.episode.evaluator.stage_ids[k]}' done at step {self.episode.steps - 1}")
            self._latched = record.stage_latched.copy()
            if self.stop_on_success and record.stable:
                self.recording, self.ended_by = False, "stable_success"
            elif self.episode.steps >= self.horizon:
                self.recording, self.ended_by = False, "horizon"
            if not self.recording:
                self.say(f"episode {self.episode_id}: {self.ended_by.replace('_', ' ')} after {self.episode.steps} "
                         f"steps; recording stopped: save or discard")
        self.step_count += 1

    def run(self, controls: list, realtime: bool = True, until: Callable[[int], bool] | None = None) -> Pacer:
        """Poll the controls and step until ``quit`` (or ``until(step)``); an open episode at the
        end is discarded with a message. Returns the pacer (its ``late_steps``)."""
        pacer = Pacer(realtime)
        try:
            while not self.quit_requested:
                for control in controls:
                    for request in control.poll(self.step_count):
                        if self.quit_requested:
                            request.reply(False, "the session is ending")
                        else:
                            request.reply(*self.handle(request.command))
                if self.quit_requested or (until is not None and until(self.step_count)):
                    break
                if self.homed:
                    pacer.resync()
                    self.homed = False
                self.step()
                pacer.wait()
        finally:
            if self.episode is not None:
                self.say(f"episode {self.episode_id} was not saved ({self.episode.steps} steps discarded)")
                self.episode = None
        return pacer
