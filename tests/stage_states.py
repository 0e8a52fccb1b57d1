"""Put a built scene into a described state and evaluate one stage predicate on it.

A state (see task_stage_states.yaml) moves free objects and sets articulated joints:

    objects:
      paper: {at: trash_can, offset: [0, 0, -0.05]}        # offset in the reference's frame
      cleaner: {at: bowl_centre, offset: [0, 0, 0.1], euler_deg: [0, 70, 0], vel: [0, 0, 0]}
      bowl: {at: left_hand, offset: [0, 0.03, -0.08]}      # the palm centre of a hand
      marker: {xyz: [0.3, 0.0, 0.02]}                      # table-relative world position
    joints: {trash_can/lid: 1.2}

Orientation is `euler_deg` in the world (default: upright, yaw 0). Objects not named keep their
place. Stateful predicates get a list of states, evaluated in order; the value after the last counts.
`{press: piano/C3, depth: -0.009}` is shorthand for two states: the key down, then back at 0.

Whole episodes (task_terminal_states.yaml) are state lists run through the task's evaluator; there
`{sat_of: stage}` stands for that stage's satisfying states and `{replay: done}` for the task's
`done` list.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from evaluation import EpisodeEvaluator, EpisodeRecord
from evaluation.predicates import compile_condition
from evaluation.step import EvalStep
from sim import physics
from sim.scene.builder import Scene
from sim.scene.parts import euler_quat, quat_matrix
from sim.scene.state import SceneObserver


def _reference(scene: Scene, observer: SceneObserver, data, name: str):
    """World position and rotation of an object, a task point (table-relative) or a hand's palm."""
    if name in scene.object_names:
        o = observer.object_states(data, [name])[name]
        return o.pos, quat_matrix(o.quat)
    if name in scene.task.points:
        p = np.array(scene.task.points[name], float)
        return p + [0, 0, scene.table_height], np.eye(3)
    hands = observer.state(data).hands
    side = name.removesuffix("_hand")
    if side in hands:
        return hands[side], np.eye(3)
    raise KeyError(f"state reference {name!r}: not an object, a point or left_hand/right_hand")


def apply_state(scene: Scene, observer: SceneObserver, data: mujoco.MjData, state: dict) -> None:
    for joint, value in (state.get("joints") or {}).items():
        data.qpos[scene.joint_qpos_adr[joint]] = value
    for name, place in (state.get("objects") or {}).items():
        if "xyz" in place:
            pos = np.array(place["xyz"], float) + [0, 0, scene.table_height]
        else:
            ref, rot = _reference(scene, observer, data, place["at"])
            pos = ref + rot @ np.array(place.get("offset", [0, 0, 0]), float)
        qa, da = scene.object_qpos_adr[name], scene.object_dof_adr[name]
        data.qpos[qa: qa + 3] = pos
        data.qpos[qa + 3: qa + 7] = euler_quat(place.get("euler_deg", [0, 0, 0]))
        data.qvel[da: da + 6] = 0.0
        data.qvel[da: da + 3] = place.get("vel", [0, 0, 0])
        mujoco.mj_forward(scene.model, data)
    mujoco.mj_forward(scene.model, data)


def expand(states, stage_states: dict | None = None, episodes: dict | None = None) -> list[dict]:
    """Plain states from the shorthands: press, sat_of (a stage's satisfying states, from
    `stage_states`) and replay (another state list of the task, from `episodes`)."""
    states = [states] if isinstance(states, dict) else list(states)
    out = []
    for state in states:
        if "sat_of" in state:
            out += expand(stage_states[state["sat_of"]]["sat"], stage_states, episodes)
        elif "replay" in state:
            out += expand(episodes[state["replay"]], stage_states, episodes)
        elif "press" in state:
            out += [{"joints": {state["press"]: state["depth"]}}, {"joints": {state["press"]: 0.0}}]
        else:
            out.append(state)
    return out


def stage_value(scene: Scene, stage: dict, states) -> bool:
    """The stage predicate's value after the given states, from the scene's home state."""
    observer = SceneObserver(scene)
    ids = [s["id"] for s in scene.task.metrics.get("stages", [])]
    cond = compile_condition(stage["predicate"], observer.context, field=f"stage {stage['id']}", stage_ids=ids,
                             allow_latched=False)
    data = scene.home_data()
    initial = observer.state(data)
    value = False
    for k, state in enumerate(expand(states)):
        apply_state(scene, observer, data, state)
        data.time = (k + 1) * physics.CONTROL_DT
        value = bool(cond(EvalStep(observer.state(data), observer.context, initial, physics.CONTROL_DT, {}, {})))
    return value


def episode_record(scene: Scene, states, stage_states: dict, episodes: dict) -> EpisodeRecord:
    """Run the task's own evaluator over an episode made of placed states: the scene as built, then
    each state for one control step, then the last state held for the dwell time and one step more
    (a terminal predicate that holds there reaches stable success)."""
    observer = SceneObserver(scene)
    evaluator = EpisodeEvaluator(scene.task.metrics, observer.context, source=str(scene.task.source))
    data = scene.home_data()
    dt = physics.CONTROL_DT
    sequence = expand(states, stage_states, episodes)
    hold = math.ceil(evaluator.dwell.dwell_s / dt) + 1
    for k in range(1 + len(sequence) + hold):
        if 1 <= k <= len(sequence):
            apply_state(scene, observer, data, sequence[k - 1])
        data.time = k * dt
        evaluator.update(observer.state(data), dt)
    return evaluator.result()
