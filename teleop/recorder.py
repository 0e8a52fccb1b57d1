"""The online recorder: per control step it stores the action executed next, then the post-step
robot and object state and the evaluator state, plus the seed, scene sample and exact initial
state, so the replay stage can reproduce the episode bit for bit.

Its per-step storing is a handful of fancy-index reads from MjData into preallocated buffer rows;
`b2d bench recorder` measures it, the scene snapshot and the evaluator update against the physics
step. Operators driven by a stream (teleop/session.py) also report, per step, the stream's
``StepFlag`` bits and their reasons; they go into ``step_flags`` / ``step_reasons``, and the stream's
input of the step (``StreamStep``: the frame that reached the sanitizer, or None, and the step's
time on the stream's clock) goes into the same buffer's stream rows, the raw recording's
``operator_stream`` (a few more row copies per step; `b2d bench recorder` times them).
"""

from __future__ import annotations

from dataclasses import asdict
from typing import NamedTuple, Protocol

import mujoco
import numpy as np

from episodes.raw import STREAM_FIELDS, OperatorStreamRecord, RawRecording
from evaluation.evaluator import EpisodeEvaluator
from evaluation.records import StepRecord
from sim import physics
from sim.scene.builder import Scene
from sim.scene.state import SceneObserver
from sim.state_io import get_state


class StreamStep(NamedTuple):
    """One control step's input from the operator stream, as the sanitizer received it."""

    frame: object | None        # teleop.streams.OperatorFrame, or None: nothing arrived this step
    clock_ns: int | None        # the step's time on the stream's clock (None: not known yet)


def stream_settings(nominal_period_ns: int | None, translation_scale: float, retarget_config) -> dict:
    """What, besides the frames, decides the commands a stream produces: the sanitizer's frame
    period, the wrist translation scale and the DexPilot configuration (a dataclass)."""
    return {"nominal_period_ns": None if nominal_period_ns is None else int(nominal_period_ns),
            "translation_scale": float(translation_scale), "retarget": asdict(retarget_config)}


class Operator(Protocol):
    """Plays the person. Optionally, after each ``act`` an operator exposes ``step_flags`` (int,
    StepFlag bits) and ``step_reasons`` (str, one reason per line) of that step; operators without
    them record 0 / "". An operator driven by a stream also exposes ``stream_settings`` (dict, see
    ``stream_settings``; available from construction) and, after each ``act``, ``stream_step``
    (``StreamStep``): the recording then keeps the stream."""

    name: str

    def reset(self, scene: Scene, data: mujoco.MjData) -> None: ...
    def act(self, step: int, data: mujoco.MjData) -> np.ndarray: ...
    def done(self, step: int) -> bool: ...


class StepBuffer:
    """Preallocated per-step arrays, grown by doubling; a step claims its row with ``next_row``."""

    def __init__(self, shapes: dict[str, tuple], dtypes: dict[str, type], capacity: int = 1024):
        self.arrays = {k: np.zeros((capacity, *s), dtype=dtypes.get(k, np.float64)) for k, s in shapes.items()}
        self.count = 0
        self.notes: dict[int, str] = {}      # step -> text, only for the (rare) steps that have one

    def next_row(self) -> int:
        """Claim the next step's row (growing the arrays when full) and return its index."""
        if self.count == next(iter(self.arrays.values())).shape[0]:
            self.arrays = {k: np.concatenate([a, np.zeros_like(a)]) for k, a in self.arrays.items()}
        self.count += 1
        return self.count - 1

    def result(self) -> dict[str, np.ndarray]:
        return {k: a[: self.count].copy() for k, a in self.arrays.items()}

    def note_list(self) -> list[str]:
        return [self.notes.get(i, "") for i in range(self.count)]


def home(scene: Scene) -> mujoco.MjData:
    """Move to the home configuration (paper: 60 homing steps) and let objects settle."""
    data = scene.home_data()
    for _ in range(physics.HOMING_STEPS):
        physics.step_control(scene.model, data, scene.layout.home_ctrl)
    return data


STREAM_ROW = {key: f"stream/{key}" for key in STREAM_FIELDS}     # the stream's rows in a StepBuffer


def new_buffer(scene: Scene, n_stages: int, stream: bool = False) -> StepBuffer:
    """The recorder's rows; with ``stream`` also the operator stream's (``STREAM_ROW``)."""
    n_obj, n_joint = len(scene.object_names), len(scene.layout.joint_names)
    shapes = {"action": (scene.model.nu,), "robot_qpos": (n_joint,), "robot_qvel": (n_joint,),
              "object_pose": (n_obj, 7), "terminal": (), "stage_latched": (n_stages,), "step_flags": ()}
    dtypes = {"terminal": bool, "stage_latched": bool, "step_flags": np.uint8}
    if stream:
        for key, (shape, _, dtype) in STREAM_FIELDS.items():
            shapes[STREAM_ROW[key]], dtypes[STREAM_ROW[key]] = shape, dtype
    return StepBuffer(shapes, dtypes)


def record_step(observer: SceneObserver, evaluator: EpisodeEvaluator, buf: StepBuffer,
                data: mujoco.MjData, action: np.ndarray, flags: int = 0, reasons: str = "",
                policy_query: bool | None = None, stream: StreamStep | None = None):
    """The recorder's work after one control step: snapshot, evaluator update, store (with the
    operator stream's flags for the step and, when flagged, why). `b2d bench recorder` times the
    same three calls one by one. ``policy_query``: the closed-loop runner says whether the policy was
    queried this step, and the evaluator then counts control steps and queries (None: not counted)."""
    counts = {} if policy_query is None else {"control_step": True, "policy_query": policy_query}
    record = evaluator.update(observer.state(data), physics.CONTROL_DT, **counts)
    store_step(observer, buf, data, action, record, flags, reasons, stream)
    return record


def store_step(observer: SceneObserver, buf: StepBuffer, data: mujoco.MjData, action: np.ndarray,
               record: StepRecord, flags: int = 0, reasons: str = "", stream: StreamStep | None = None) -> None:
    """Copy one step into the buffer's next rows straight from MjData: a fancy-index read per array
    into its preallocated row, no per-object work. ``stream``: the step's operator-stream input, for
    a buffer made with ``stream=True``."""
    i = buf.next_row()
    a = buf.arrays
    a["action"][i] = action
    data.qpos.take(observer.robot_qpos_idx, out=a["robot_qpos"][i])     # the method: np.take's wrapper
    data.qvel.take(observer.robot_dof_idx, out=a["robot_qvel"][i])      # costs as much as the copy
    observer.object_pose_into(data, a["object_pose"][i])
    a["terminal"][i] = record.terminal
    a["stage_latched"][i] = record.stage_latched
    a["step_flags"][i] = flags
    if reasons:
        buf.notes[i] = reasons
    if stream is not None:
        store_stream(a, i, stream)


def store_stream(a: dict[str, np.ndarray], i: int, stream: StreamStep) -> None:
    """The step's stream input into row ``i`` (rows start zeroed: nothing arrived, no clock)."""
    frame = stream.frame
    if frame is not None:
        a["stream/arrived"][i] = True
        a["stream/timestamp_ns"][i] = frame.timestamp_ns
        a["stream/keypoints"][i] = frame.keypoints
        a["stream/wrist_pos"][i] = frame.wrist_pos
        a["stream/wrist_quat"][i] = frame.wrist_quat
        a["stream/keypoints_valid"][i] = frame.keypoints_valid
        a["stream/wrist_valid"][i] = frame.wrist_valid
    if stream.clock_ns is not None:
        a["stream/clock_ns"][i] = stream.clock_ns
        a["stream/clock_known"][i] = True


HORIZON_FACTOR = 1.5            # paper: the evaluation horizon is 1.5x the recorded expert horizon
NO_EXPERT_HORIZON_STEPS = 10_000


def evaluation_horizon(metrics: dict) -> int:
    """Control steps an episode may run: 1.5x the task's expert horizon (either spelling the evaluator
    accepts), or NO_EXPERT_HORIZON_STEPS for a task without one."""
    expert = metrics.get("expert_horizon_steps", metrics.get("expert_time_step"))
    return int(HORIZON_FACTOR * expert) if expert else NO_EXPERT_HORIZON_STEPS


def episode_horizon(scene: Scene, max_steps: int | None = None) -> int:
    horizon = evaluation_horizon(scene.task.metrics)
    return horizon if max_steps is None else min(horizon, max_steps)


class EpisodeRecording:
    """One episode being recorded, from the homed state ``data``: ``step`` after each control step,
    ``finish`` assembles the raw recording. With ``stream_settings`` (an operator stream drives the
    robot) every step also gives its ``StreamStep`` and the recording keeps the stream."""

    def __init__(self, scene: Scene, data: mujoco.MjData, stream_settings: dict | None = None):
        self.scene = scene
        self.initial_state = get_state(scene.model, data)
        self.observer = SceneObserver(scene)
        self.evaluator = EpisodeEvaluator(scene.task.metrics, self.observer.context, source=str(scene.task.source))
        self.stream_settings = stream_settings
        self.buf = new_buffer(scene, len(self.evaluator.stage_ids), stream=stream_settings is not None)

    @property
    def steps(self) -> int:
        return self.buf.count

    def step(self, data: mujoco.MjData, action: np.ndarray, flags: int = 0, reasons: str = "",
             policy_query: bool | None = None, stream: StreamStep | None = None):
        if (stream is None) != (self.stream_settings is None):
            raise ValueError("a recording with stream_settings takes a StreamStep every step, one without takes none")
        return record_step(self.observer, self.evaluator, self.buf, data, action, flags, reasons, policy_query,
                           stream)

    def finish(self, episode_id: str, seed: int, operator: str, termination: str | None = None,
               extra: dict | None = None, error: str | None = None) -> RawRecording:
        scene, model = self.scene, self.scene.model
        result = self.evaluator.result(termination=termination or ("stable_success" if self.evaluator.stable
                                                                   else "horizon"), error=error)
        rows = self.buf.result()
        stream = None
        if self.stream_settings is not None:
            stream = OperatorStreamRecord(**{k: rows.pop(STREAM_ROW[k]) for k in STREAM_FIELDS},
                                          settings=dict(self.stream_settings))
        return RawRecording(
            task=scene.task.name, embodiment=scene.layout.embodiment, episode_id=episode_id, seed=seed,
            scene_sample=scene.sample.to_json(), operator=operator, control_hz=physics.CONTROL_HZ,
            substeps=physics.SUBSTEPS, initial_state=self.initial_state,
            actuator_names=[model.actuator(i).name for i in range(model.nu)],
            robot_joint_names=list(scene.layout.joint_names), object_names=list(scene.object_names),
            stage_ids=list(self.evaluator.stage_ids), success=bool(result.success), **rows,
            extra={"lscr": float(result.lscr or 0.0), "episode_record": result.to_dict(), **(extra or {})},
            step_reasons=self.buf.note_list(), hand_model=scene.layout.hand_model, stream=stream,
        )


def record_episode(scene: Scene, operator: Operator, episode_id: str, seed: int,
                   max_steps: int | None = None, stop_on_success: bool = True) -> RawRecording:
    data = home(scene)
    settings = getattr(operator, "stream_settings", None)      # a stream operator: keep its stream
    episode = EpisodeRecording(scene, data, stream_settings=settings)
    operator.reset(scene, data)
    horizon = episode_horizon(scene, max_steps)
    step = 0
    while step < horizon and not operator.done(step):
        action = operator.act(step, data)
        physics.step_control(scene.model, data, action)
        record = episode.step(data, action, getattr(operator, "step_flags", 0), getattr(operator, "step_reasons", ""),
                              stream=operator.stream_step if settings is not None else None)
        step += 1
        if stop_on_success and record.stable:
            break    # reach-and-stop
    return episode.finish(episode_id, seed, operator.name)
