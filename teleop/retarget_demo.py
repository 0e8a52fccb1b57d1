"""A recorded demonstration onto another embodiment (`b2d retarget RAW --embodiment E`).

A raw recording made through an operator stream (`b2d record --operator stream`, `b2d teleop`)
keeps, per control step, the stream's input: the frame that reached the sanitizer (or none) and the
step's time on the stream's clock (episodes/raw.py, ``operator_stream``). Here that input is fed,
step by step, through embodiment E's stream driver (``teleop/session_driver.py``: the live session's
sanitizer, DexPilot per hand and arm CLIK, with the recording's own sanitizer period, translation
scale and DexPilot settings) in the same task's scene (the recording's scene sample, or a seed's),
and the online recorder writes a new raw recording with E's actions and states; the evaluator
scores it as any episode. On the recording's own embodiment this reproduces its actions.

The person is not in the loop: nobody corrects the hand that now misses. Wrist motion, two ways:

* ``session`` (default): as in a live session, relative to the anchor taken at the first wrist
  pose and applied from E's home, so a hand whose home sits elsewhere (the Panda's, 10 cm further
  forward) moves by as much from there;
* ``world``: E's hand base follows the original hand base's path in the world, as a tracker
  calibrated to the robot's world would make it: the anchors are set before the first frame to
  ``anchor_o @ base_home_o^-1 @ base_home_E`` (``o``: the recording's embodiment), kept in the new
  recording's stream settings (``wrist_anchors``) so that it replays from its own stream.

After the stream ends the operator holds still for ``hold_steps`` (the last frame again,
one frame period later each step), so a grasp that settles a little later than on the original
embodiment can still reach its dwell; recording stops at stable success, as `b2d record`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import numpy as np

from episodes.atomic import file_sha256
from episodes.raw import STREAM, OperatorStreamRecord, RawRecording, read_raw, write_raw
from sim import physics
from sim.embodiment.description import Transform, quat_to_mat
from sim.errors import SpecError
from sim.registry import validate_name
from sim.scene.builder import build_scene
from sim.scene.sample import SceneSample, demonstration_sample
from sim.tasks import load_task
from teleop.demos import raw_filename
from teleop.recorder import EpisodeRecording, StreamStep, episode_horizon, home
from teleop.retarget import DexPilotConfig, TeleopCommander
from teleop.session_driver import StreamDriver, session_time_ns
from teleop.session_inputs import SessionInput
from teleop.streams import SIDES, OperatorFrame, StreamSanitizer

DEFAULT_HOLD_STEPS = 60     # 1 s: longer than the evaluator's 0.5 s dwell
WRIST_MODES = ("session", "world")
NO_STREAM = ("the operator stream that produced the actions (this recording has none: it was made with "
             "`b2d record --operator scripted` or before streams were recorded); record one with "
             "`b2d record --operator stream` or `b2d teleop`")


@dataclass(frozen=True)
class RetargetedEpisode:
    source: Path
    path: Path
    embodiment: str
    steps: int
    success: bool
    stages_reached: list[str]       # latched at some step
    stages_held: list[str]          # still true at the end (an object knocked off again is not)
    stage_ids: list[str]
    flagged_steps: int

    def summary(self) -> str:
        n = len(self.stage_ids)
        reached = f" ({', '.join(self.stages_reached)})" if self.stages_reached else ""
        held = f", {len(self.stages_held)}/{n} held at the end" if self.stages_held != self.stages_reached else ""
        return (f"{self.source} -> {self.path}: {self.embodiment} {'success' if self.success else 'no success'}, "
                f"stages {len(self.stages_reached)}/{n}{reached}{held}, steps={self.steps}, "
                f"flagged={self.flagged_steps}")


def retarget_config(stream: OperatorStreamRecord, source=None) -> DexPilotConfig:
    try:
        return DexPilotConfig(**stream.settings["retarget"])
    except TypeError as exc:
        raise SpecError(source, f"{STREAM}/settings", "'retarget' with DexPilotConfig fields "
                        f"{[f.name for f in dataclasses.fields(DexPilotConfig)]}", str(exc)) from None


def recorded_steps(stream: OperatorStreamRecord) -> Iterator[StreamStep]:
    """The recording's per-step stream input, as the sanitizer received it."""
    for i in range(stream.num_steps):
        frame = _stored_frame(stream, i, int(stream.timestamp_ns[i])) if stream.arrived[i] else None
        yield StreamStep(frame, int(stream.clock_ns[i]) if stream.clock_known[i] else None)


def _stored_frame(stream: OperatorStreamRecord, row: int, timestamp_ns: int) -> OperatorFrame:
    """The operator frame stored in `row`, stamped `timestamp_ns`."""
    return OperatorFrame(timestamp_ns, stream.keypoints[row], stream.wrist_pos[row], stream.wrist_quat[row],
                         stream.keypoints_valid[row], stream.wrist_valid[row])


def held_steps(stream: OperatorStreamRecord, count: int) -> Iterator[StreamStep]:
    """The operator holding still after the stream: its last frame again, one frame period (else one
    control period) later each step, on a clock that moves on as much."""
    arrived = np.flatnonzero(stream.arrived)
    if not count or not arrived.size:
        return
    last = arrived[-1]
    period = stream.settings["nominal_period_ns"] or session_time_ns(1)
    clock = next((int(stream.clock_ns[i]) for i in range(stream.num_steps - 1, -1, -1) if stream.clock_known[i]), None)
    for k in range(1, count + 1):
        frame = _stored_frame(stream, last, int(stream.timestamp_ns[last]) + k * period)
        yield StreamStep(frame, None if clock is None else clock + k * period)


def anchor_values(anchor: Transform) -> list[float]:
    return [*map(float, anchor.pos), *map(float, anchor.quat)]


def anchor_transform(values) -> Transform:
    return Transform(np.asarray(values[:3], float), quat_to_mat(np.asarray(values[3:], float)))


def first_wrist_poses(stream: OperatorStreamRecord) -> dict[str, Transform]:
    """Per side, the wrist pose the recording's commander anchored on: its preset anchor, else the
    first one the sanitizer accepted (as ``TeleopCommander.wrist_site_target`` takes it)."""
    preset = stream.settings.get("wrist_anchors") or {}
    anchors = {side: anchor_transform(v) for side, v in preset.items()}
    sanitizer = StreamSanitizer(stream.settings["nominal_period_ns"])
    for step in recorded_steps(stream):
        if len(anchors) == len(SIDES):
            break
        checked = sanitizer.step(*step)
        for i, side in enumerate(SIDES):
            if side not in anchors and checked.fresh_wrist[i]:
                anchors[side] = Transform(checked.frame.wrist_pos[i].copy(), quat_to_mat(checked.frame.wrist_quat[i]))
    return anchors


def world_wrist_anchors(raw: RawRecording, commander: TeleopCommander) -> dict[str, list[float]]:
    """Anchors that make ``commander``'s hand bases follow the recording's hand-base paths in the world."""
    original = build_scene(load_task(raw.task), raw.embodiment, SceneSample.from_json(raw.scene_sample),
                           hand_model=raw.hand_model)
    before = TeleopCommander(original.model, original.layout).sides
    return {side: anchor_values(anchor @ before[side].base_home.inverse() @ commander.sides[side].base_home)
            for side, anchor in first_wrist_poses(raw.stream).items()}


def retarget_recording(raw: RawRecording, embodiment: str, source=None, seed: int | None = None,
                       hold_steps: int = DEFAULT_HOLD_STEPS, max_steps: int | None = None,
                       stop_on_success: bool = True, sha256: str | None = None, wrist: str = "session") -> RawRecording:
    """``raw``'s operator stream replayed onto ``embodiment``: a new raw recording (not written).
    ``seed``: the scene from this seed's demonstration sample instead of the recording's own;
    ``wrist``: one of ``WRIST_MODES`` (module docstring)."""
    validate_name("embodiment", embodiment)
    if wrist not in WRIST_MODES:
        raise ValueError(f"wrist: expected one of {list(WRIST_MODES)}, got {wrist!r}")
    if raw.stream is None:
        raise SpecError(source, STREAM, NO_STREAM, raw.operator)
    spec = load_task(raw.task)
    sample = SceneSample.from_json(raw.scene_sample) if seed is None else demonstration_sample(spec, seed)
    scene = build_scene(spec, embodiment, sample, hand_model=raw.hand_model if embodiment == raw.embodiment else None)
    settings = dict(raw.stream.settings)
    replayed = SessionInput(stream=None, name="retarget", spec=str(source or raw.episode_id), recorded=None,
                            nominal_period_ns=settings["nominal_period_ns"],
                            description=f"the operator stream of {source or raw.episode_id}")
    driver = StreamDriver(replayed, settings["translation_scale"], retarget_config(raw.stream, source))
    driver.attach(scene)
    if embodiment != raw.embodiment:      # the recording's own anchors are kept only where they were taken
        settings.pop("wrist_anchors", None)
        if wrist == "world":
            settings["wrist_anchors"] = world_wrist_anchors(raw, driver.commander)
    anchors = {side: anchor_transform(v) for side, v in (settings.get("wrist_anchors") or {}).items()}
    data = home(scene)               # as a session's start: home, then filters and anchors forgotten
    driver.reset()
    for side, anchor in anchors.items():       # a tracker calibrated to the world: no anchoring on the first pose
        driver.commander.sides[side].anchor = anchor
    episode = EpisodeRecording(scene, data, stream_settings={**driver.stream_settings, **settings})
    horizon = episode_horizon(scene, max_steps)
    inputs = [*recorded_steps(raw.stream), *held_steps(raw.stream, hold_steps)]
    for step in inputs[:horizon]:
        cmd = driver.command_for(*step)
        physics.step_control(scene.model, data, cmd.ctrl)
        record = episode.step(data, cmd.ctrl, int(cmd.flags), "\n".join(cmd.reasons), stream=driver.last_step)
        if stop_on_success and record.stable:
            break
    ended = ("stable_success" if episode.evaluator.stable else "horizon" if episode.steps >= horizon
             else "stream_end")      # the recorded stream and the hold ran out first
    origin = {"file": Path(source).name if source else None, "sha256": sha256, "embodiment": raw.embodiment,
              "operator": raw.operator, "seed": raw.seed, "steps": raw.num_steps, "success": raw.success}
    return episode.finish(raw.episode_id, raw.seed if seed is None else seed, f"retarget:{raw.operator}", ended,
                          extra={"retargeted_from": origin, "hold_steps": hold_steps, "wrist": wrist})


def retarget_file(path: str | Path, embodiment: str, out_dir: str | Path | None = None, **options) -> RetargetedEpisode:
    """Read ``path``, retarget it onto ``embodiment`` and write the result atomically as
    ``<out_dir>/episode_<id>.raw.h5`` (default out_dir: ``<path's folder>/retarget/<embodiment>``)."""
    path = Path(path)
    raw = read_raw(path)
    out_dir = Path(out_dir) if out_dir is not None else path.parent / "retarget" / embodiment
    out = out_dir / raw_filename(raw.episode_id)
    if out.resolve() == path.resolve():
        raise SpecError(path, "--out", "a folder other than the recording's own (it would be overwritten)",
                        str(out_dir))
    rec = retarget_recording(raw, embodiment, source=path, sha256=file_sha256(path), **options)
    write_raw(out, rec)
    reached = [s for s, done in zip(rec.stage_ids, rec.stage_latched[-1]) if done]
    final = rec.extra["episode_record"].get("stage_final") or [False] * len(rec.stage_ids)
    held = [s for s, done in zip(rec.stage_ids, final) if done]
    return RetargetedEpisode(path, out, embodiment, rec.num_steps, rec.success, reached, held, list(rec.stage_ids),
                             int(np.count_nonzero(rec.step_flags)))
