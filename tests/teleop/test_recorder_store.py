"""The recorder's fast paths give the values of the plain formulas, bit for bit: buffer rows read with
precomputed indices (`store_step`), the observer's stacked reads, contact pairs and object speeds, and
the evaluator's cached rotation matrices."""

from __future__ import annotations

import functools
import math

import mujoco
import numpy as np
import pytest

from evaluation.evaluator import EpisodeEvaluator
from evaluation.geometry import _rotation, length, rotation
from sim import physics
from sim.scene.builder import demonstration_scene
from sim.scene.state import SceneObserver
from teleop.recorder import new_buffer, store_step
from plan_runs import home_and_plan

STEPS = 120
# citrus: every object free; microwave: a fixed-base microwave (its pose comes from the model) and a door joint
SETTINGS = [("citrus_plate_loading", "ur5_rh5dg2"), ("microwave_bowl_loading", "ur5_rh5dg2")]


@functools.lru_cache(maxsize=None)
def rollout(task: str, embodiment: str):
    """STEPS scripted control steps through the recorder's snapshot, evaluator and store, keeping a
    copy of MjData after each step for the reference formulas."""
    scene = demonstration_scene(task, embodiment)
    data, op = home_and_plan(scene)
    observer = SceneObserver(scene)
    evaluator = EpisodeEvaluator(scene.task.metrics, observer.context)
    buf = new_buffer(scene, len(evaluator.stage_ids))
    buf.arrays = {k: a[:16] for k, a in buf.arrays.items()}     # small, so the rollout also grows it
    snapshots, states, actions = [], [], []
    for t in range(STEPS):
        action = op.act(t, data)
        physics.step_control(scene.model, data, action)
        state = observer.state(data)
        record = evaluator.update(state, physics.CONTROL_DT)
        store_step(observer, buf, data, action, record, flags=t % 3, reasons="r" if t % 3 else "")
        snapshots.append(mujoco.MjData(scene.model))
        mujoco.mj_copyData(snapshots[-1], scene.model, data)
        states.append(state)
        actions.append(action)
    return scene, buf.result(), buf.note_list(), evaluator, snapshots, states, actions


def reference_pose(scene, data, name: str) -> np.ndarray:
    if name in scene.object_qpos_adr:
        qa = scene.object_qpos_adr[name]
        return data.qpos[qa: qa + 7].copy()
    bid = scene.object_body_ids[name]
    return np.concatenate([scene.model.body_pos[bid], scene.model.body_quat[bid]])


def owners(scene) -> dict[int, str]:
    """Body id -> contact name: task objects (and the bodies of their joints), the table, the hands."""
    model = scene.model
    out = {bid: name for name, bid in scene.object_body_ids.items()}
    out.update({model.body(j).id: j.split("/")[0] for j in scene.joint_names})
    out[model.body("table").id] = "table"
    for side, layout in scene.layout.sides.items():
        out.update({model.body(b).id: f"{side}_hand" for b in layout.hand_bodies})
    return out


@pytest.mark.parametrize("setting", SETTINGS, ids=lambda s: s[0])
def test_stored_rows_equal_the_plain_formulas(setting):
    scene, arrays, notes, evaluator, snapshots, _, actions = rollout(*setting)
    assert len(arrays["action"]) == STEPS
    for t, data in enumerate(snapshots):
        assert arrays["action"][t].tobytes() == np.asarray(actions[t], dtype=float).tobytes()
        assert arrays["robot_qpos"][t].tobytes() == data.qpos[scene.robot_qpos_adr].tobytes()
        assert arrays["robot_qvel"][t].tobytes() == data.qvel[scene.robot_dof_adr].tobytes()
        pose = np.stack([reference_pose(scene, data, n) for n in scene.object_names])
        assert arrays["object_pose"][t].tobytes() == pose.tobytes()
        step = evaluator.steps[t]
        assert arrays["terminal"][t] == step.terminal
        assert arrays["stage_latched"][t].tobytes() == step.stage_latched.tobytes()
        assert arrays["step_flags"][t] == t % 3 and notes[t] == ("r" if t % 3 else "")


@pytest.mark.parametrize("setting", SETTINGS, ids=lambda s: s[0])
def test_snapshot_equals_the_plain_formulas(setting):
    scene, _, _, _, snapshots, states, _ = rollout(*setting)
    model, owner = scene.model, owners(scene)
    touching = 0
    for data, state in zip(snapshots, states):
        assert list(state.objects) == list(scene.object_names)
        for name, o in state.objects.items():
            pose = reference_pose(scene, data, name)
            assert o.pos.tobytes() == pose[:3].tobytes() and o.quat.tobytes() == pose[3:].tobytes()
            if name in scene.object_dof_adr:
                da, bid = scene.object_dof_adr[name], scene.object_body_ids[name]
                assert o.lin_vel.tobytes() == data.qvel[da: da + 3].tobytes()
                spin = data.xmat[bid].reshape(3, 3) @ data.qvel[da + 3: da + 6]
                assert o.ang_vel.tobytes() == spin.tobytes()
            else:
                assert not o.lin_vel.any() and not o.ang_vel.any()
            assert o.speed == length(o.lin_vel) and o.spin == length(o.ang_vel)
        pairs = set()
        for i in range(data.ncon):
            a, b = (owner.get(int(model.geom_bodyid[g]), "") for g in data.contact.geom[i])
            if a and b and a != b:
                pairs.add(tuple(sorted((a, b))))
        assert state.contacts == frozenset(pairs)
        touching += bool(pairs)
        assert state.joints == {j: float(data.qpos[scene.joint_qpos_adr[j]]) for j in scene.joint_names}
        for side, layout in scene.layout.sides.items():
            assert state.hands[side].tobytes() == data.site_xpos[model.site(layout.wrist_site).id].tobytes()
    assert touching > STEPS // 2       # objects rest on the table: the contact path was exercised


def test_fixed_base_states_cannot_be_changed_in_place():
    scene, _, _, _, _, states, _ = rollout(*SETTINGS[1])
    fixed = [n for n in scene.object_names if n not in scene.object_qpos_adr]
    assert fixed
    with pytest.raises(ValueError):
        states[0].objects[fixed[0]].pos[0] = 1.0


def test_cached_rotation_is_the_computed_one_and_read_only():
    rng = np.random.default_rng(7)
    for _ in range(300):
        q = rng.normal(size=4)
        fresh = _rotation(q.copy())
        assert rotation(q).tobytes() == fresh.tobytes()
        assert rotation(list(q)).tobytes() == fresh.tobytes()      # lists too, same key
        assert rotation(q) is rotation(q.copy())                   # keyed by value
    with pytest.raises(ValueError):
        rotation(q)[0, 0] = 2.0
    w, x, y, z = q / math.sqrt(float(np.dot(q, q)))
    assert rotation(q)[2, 2] == 1 - 2 * (x * x + y * y)


def test_bench_recorder_reports_each_part_against_both_physics_baselines():
    from b2d_cli.benchmarks import bench_recorder

    f = bench_recorder(12)
    ms = f["ms_per_control_step"]
    assert set(ms) == {"physics_control_step", "physics_mj_step", "recording", "evaluation", "evaluation_snapshot",
                       "evaluation_update", "recording_with_stream"}
    assert f["recording_with_stream_vs_recording"] > 0      # the stream's rows, timed on the same steps
    assert all(v > 0 for v in ms.values()) and set(f["median_ms_per_control_step"]) == set(ms)
    assert ms["evaluation"] == pytest.approx(ms["evaluation_snapshot"] + ms["evaluation_update"], abs=2e-4)
    assert ms["physics_mj_step"] < ms["physics_control_step"]       # a control step is SUBSTEPS of them
    def ratio(num: str, den: str):     # the ms figures and the ratios are rounded to 1e-4: allow for both
        return pytest.approx(ms[num] / ms[den], rel=1e-2, abs=1e-4 / ms[den] + 1e-4)

    assert f["recording_vs_mj_step"] == ratio("recording", "physics_mj_step")
    assert f["recording_vs_control_step"] == ratio("recording", "physics_control_step")
    assert f["evaluation_vs_control_step"] == ratio("evaluation", "physics_control_step")
