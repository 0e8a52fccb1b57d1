"""Benchmarks that print figures (`b2d bench recorder|replay`), with baselines from the same run."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from episodes.stages import assemble_episode, render_to_file, replay_to_file
from sim import physics
from sim.registry import names, sensor_profile
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample, task_seed
from sim.scene.state import SceneObserver
from sim.tasks import load_task
from teleop.demos import record_demonstrations
from teleop.recorder import home, new_buffer, record_step
from teleop.scripted_operator import ScriptedOperator

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"


def _scene():
    spec = load_task(TASK)
    return build_scene(spec, EMBODIMENT, demonstration_sample(spec, task_seed(names("tasks").index(TASK), 0)))


def bench_recorder(steps: int) -> dict:
    """Per-step cost of recording (state snapshot + evaluator + buffer) against the physics step."""
    from evaluation.evaluator import EpisodeEvaluator

    scene = _scene()
    data = home(scene)
    op = ScriptedOperator()
    op.reset(scene, data)
    actions = [op.act(t, data) for t in range(steps)]        # operator cost is not the recorder's
    observer = SceneObserver(scene)
    evaluator = EpisodeEvaluator(scene.task.metrics, observer.context)
    buf = new_buffer(scene, len(evaluator.stage_ids))
    physics_s = record_s = 0.0
    for t in range(steps):
        t0 = time.perf_counter()
        physics.step_control(scene.model, data, actions[t])
        t1 = time.perf_counter()
        record_step(scene, observer, evaluator, buf, data, actions[t])
        record_s += time.perf_counter() - t1
        physics_s += t1 - t0
    return {"steps": steps, "physics_ms_per_control_step": 1e3 * physics_s / steps,
            "recorder_ms_per_step": 1e3 * record_s / steps,
            "recorder_overhead_vs_control_step": record_s / physics_s,
            "recorder_overhead_vs_one_physics_substep": record_s / (physics_s / physics.SUBSTEPS),
            "note": "a control step is 8 MuJoCo substeps; the paper's 'physics step' is the 60 Hz step"}


def bench_replay(profile_name: str, steps: int) -> dict:
    profile = sensor_profile(profile_name)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        raw = record_demonstrations(TASK, EMBODIMENT, 1, tmp, max_steps=steps)[0].path
        t0 = time.perf_counter()
        replay_to_file(raw, tmp / "e.replay.h5")
        t1 = time.perf_counter()
        info = render_to_file(tmp / "e.replay.h5", profile, tmp / "e.render.h5")
        t2 = time.perf_counter()
        out = assemble_episode(tmp / "e.replay.h5", tmp / "e.render.h5", profile, tmp / "episode_e.hdf5")
        t3 = time.perf_counter()
    frames = info["frames"]
    total = t3 - t0
    return {"profile": profile_name, "control_steps": steps, "frames": frames,
            "frames_per_second_per_core": frames / total,
            "share": {"physics_replay": (t1 - t0) / total, "render_rgb_depth": (t2 - t1) / total,
                      "assemble_write": (t3 - t2) / total},
            "bytes_per_frame_on_disk": out["bytes"] / max(frames, 1), "seconds": total}


def run(part: str, profile: str = "preview", steps: int = 120) -> dict:
    if part == "recorder":
        return bench_recorder(steps)
    if part == "replay":
        return bench_replay(profile, steps)
    raise ValueError(part)
