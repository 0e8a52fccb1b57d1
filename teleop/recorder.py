"""The online recorder: per control step it stores the action executed next, then the post-step
robot and object state and the evaluator state, plus the seed, scene sample and exact initial
state, so the replay stage can reproduce the episode bit for bit.

Its per-step work is a handful of array copies into preallocated buffers (measured by
`b2d bench recorder`).
"""

from __future__ import annotations

from typing import Protocol

import mujoco
import numpy as np

from episodes.raw import RawRecording
from evaluation.evaluator import EpisodeEvaluator
from sim import physics
from sim.scene.builder import Scene
from sim.scene.state import SceneObserver
from sim.state_io import get_state


class Operator(Protocol):
    name: str

    def reset(self, scene: Scene, data: mujoco.MjData) -> None: ...
    def act(self, step: int, data: mujoco.MjData) -> np.ndarray: ...
    def done(self, step: int) -> bool: ...


class StepBuffer:
    """Preallocated per-step arrays, grown by doubling."""

    def __init__(self, shapes: dict[str, tuple], dtypes: dict[str, type], capacity: int = 1024):
        self.arrays = {k: np.zeros((capacity, *s), dtype=dtypes.get(k, np.float64)) for k, s in shapes.items()}
        self.count = 0

    def push(self, **values) -> None:
        if self.count == next(iter(self.arrays.values())).shape[0]:
            self.arrays = {k: np.concatenate([a, np.zeros_like(a)]) for k, a in self.arrays.items()}
        for key, value in values.items():
            self.arrays[key][self.count] = value
        self.count += 1

    def result(self) -> dict[str, np.ndarray]:
        return {k: a[: self.count].copy() for k, a in self.arrays.items()}


def home(scene: Scene) -> mujoco.MjData:
    """Move to the home configuration (paper: 60 homing steps) and let objects settle."""
    data = scene.home_data()
    for _ in range(physics.HOMING_STEPS):
        physics.step_control(scene.model, data, scene.layout.home_ctrl)
    return data


def new_buffer(scene: Scene, n_stages: int) -> StepBuffer:
    n_obj, n_joint = len(scene.object_names), len(scene.layout.joint_names)
    return StepBuffer(
        {"action": (scene.model.nu,), "robot_qpos": (n_joint,), "robot_qvel": (n_joint,),
         "object_pose": (n_obj, 7), "terminal": (), "stage_latched": (n_stages,), "step_flags": ()},
        {"terminal": bool, "stage_latched": bool, "step_flags": np.uint8})


def record_step(scene: Scene, observer: SceneObserver, evaluator: EpisodeEvaluator, buf: StepBuffer,
                data: mujoco.MjData, action: np.ndarray):
    """The recorder's work after one control step: snapshot, evaluator update, buffer push."""
    state = observer.state(data)
    record = evaluator.update(state, physics.CONTROL_DT)
    buf.push(action=action, robot_qpos=data.qpos[scene.robot_qpos_adr],
             robot_qvel=data.qvel[scene.robot_dof_adr],
             object_pose=np.stack([np.concatenate([o.pos, o.quat]) for o in state.objects.values()]),
             terminal=record.terminal, stage_latched=record.stage_latched, step_flags=0)
    return record


def record_episode(scene: Scene, operator: Operator, episode_id: str, seed: int,
                   max_steps: int | None = None, stop_on_success: bool = True) -> RawRecording:
    model = scene.model
    data = home(scene)
    initial_state = get_state(model, data)
    observer = SceneObserver(scene)
    evaluator = EpisodeEvaluator(scene.task.metrics, observer.context, source=str(scene.task.source))
    operator.reset(scene, data)
    stage_ids = evaluator.stage_ids
    buf = new_buffer(scene, len(stage_ids))
    horizon = max_steps if max_steps is not None else scene.task.metrics.get("horizon_steps") or 10_000
    step = 0
    while step < horizon and not operator.done(step):
        action = operator.act(step, data)
        physics.step_control(model, data, action)
        record = record_step(scene, observer, evaluator, buf, data, action)
        step += 1
        if stop_on_success and record.stable:
            break    # reach-and-stop
    arrays = buf.result()
    result = evaluator.result(termination="stable_success" if evaluator.stable else "horizon")
    return RawRecording(
        task=scene.task.name, embodiment=scene.layout.embodiment, episode_id=episode_id, seed=seed,
        scene_sample=scene.sample.to_json(), operator=operator.name, control_hz=physics.CONTROL_HZ,
        substeps=physics.SUBSTEPS, initial_state=initial_state,
        actuator_names=[model.actuator(i).name for i in range(model.nu)],
        robot_joint_names=list(scene.layout.joint_names), object_names=list(scene.object_names),
        stage_ids=list(stage_ids), success=bool(result.success), **arrays,
        extra={"lscr": float(result.lscr or 0.0), "episode_record": result.to_dict()},
    )
