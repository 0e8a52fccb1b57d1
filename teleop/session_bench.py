"""Per-step cost of a live session against the 60 Hz budget (`b2d bench teleop`).

A generated operator stream (both hands closing into a power grasp and then a pinch, wrists
circling a few centimetres; every 7th frame missing so the flags path is exercised) drives the
session's own loop pieces for ``steps`` control steps. Measured per step, in the same run:

* ``command_ms``: stream poll + sanitizer + DexPilot for both hands + arm IK for both arms;
* ``physics_ms``: one control step of MuJoCo (the baseline: 8 substeps);
* ``recorder_ms``: the online recorder's ``record_step`` with the step's flags and reasons, and
  ``recorder_no_flags_ms`` the same work through a second recorder given 0 / "" (the two run on the
  same states, in alternating order), so ``flags_cost_ms`` is what recording the flags adds.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from sim import physics
from sim.embodiment.description import Transform, mat_to_quat, rpy_to_matrix
from sim.registry import names
from sim.scene.builder import demonstration_scene
from teleop.recorder import EpisodeRecording, home
from teleop.retarget.bench import session_keypoints
from teleop.streams import OperatorFrame, write_stream
from teleop.streams.human_hand import MIRROR

from .session_driver import StreamDriver, session_time_ns
from .session_inputs import open_input

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"
DROP_EVERY = 7
ANCHOR = Transform(np.array([0.3, -0.2, 1.1]), rpy_to_matrix([0.3, -0.5, 1.0]))


def bench_frames(steps: int) -> list[OperatorFrame]:
    keypoints = session_keypoints(steps)
    frames = []
    for k, kp in enumerate(keypoints):
        if k % DROP_EVERY == DROP_EVERY - 1:
            continue
        a = 2 * np.pi * k / max(steps, 1)
        wrist = ANCHOR @ Transform(0.03 * np.array([np.cos(a) - 1, np.sin(a), 0.5 * np.sin(a)]),
                                   rpy_to_matrix([0.1 * np.sin(a), 0.0, 0.1 * np.cos(a) - 0.1]))
        f = OperatorFrame.empty(session_time_ns(k))
        for side, hand in (("left", kp * MIRROR), ("right", kp)):
            f = f.with_hand(side, keypoints=hand, wrist_pos=wrist.pos, wrist_quat=mat_to_quat(wrist.rot))
        frames.append(f)
    return frames


def _ms(seconds: float, steps: int) -> float:
    return round(1e3 * seconds / steps, 4)


def run_session_bench(steps: int = 600) -> dict:
    scene = demonstration_scene(TASK, EMBODIMENT)
    with tempfile.TemporaryDirectory() as tmp:
        source = open_input([f"recorded:{write_stream(Path(tmp) / 'bench.npz', bench_frames(steps))}"])
    driver = StreamDriver(source)
    driver.attach(scene)
    data = home(scene)
    driver.reset()
    flagged, plain = EpisodeRecording(scene, data), EpisodeRecording(scene, data)
    clock = time.perf_counter
    command_s = physics_s = rec_s = plain_s = 0.0
    for step in range(steps):
        t0 = clock()
        cmd = driver.command(session_time_ns(step))
        t1 = clock()
        physics.step_control(scene.model, data, cmd.ctrl)
        t2 = clock()
        command_s, physics_s = command_s + t1 - t0, physics_s + t2 - t1
        reasons = "\n".join(cmd.reasons)
        for which in ((0, 1) if step % 2 else (1, 0)):
            t0 = clock()
            if which:
                flagged.step(data, cmd.ctrl, int(cmd.flags), reasons)
            else:
                plain.step(data, cmd.ctrl)
            dt = clock() - t0
            rec_s, plain_s = (rec_s + dt, plain_s) if which else (rec_s, plain_s + dt)
    n_flagged = int(np.count_nonzero(flagged.buf.arrays["step_flags"][:steps]))
    budget_ms = 1e3 * physics.CONTROL_DT
    total = command_s + physics_s + rec_s
    return {
        "task": TASK, "embodiment": EMBODIMENT, "steps": steps, "flagged_steps": n_flagged,
        "command_ms": _ms(command_s, steps), "physics_ms": _ms(physics_s, steps),
        "recorder_ms": _ms(rec_s, steps), "recorder_no_flags_ms": _ms(plain_s, steps),
        "flags_cost_ms": _ms(rec_s - plain_s, steps),
        "recorder_vs_physics": round(rec_s / physics_s, 4),
        "flags_cost_vs_physics": round((rec_s - plain_s) / physics_s, 4),
        "step_ms": _ms(total, steps), "realtime_budget_ms": round(budget_ms, 3),
        "budget_used": round(1e3 * total / steps / budget_ms, 4),
        "note": "one core; physics = one 60 Hz control step (8 MuJoCo substeps); recorder = state snapshot + "
                "evaluator + buffer push",
    }
