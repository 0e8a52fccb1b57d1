"""Replay determinism: the same raw recording replayed twice (in two processes) gives
byte-identical arrays, and replay reproduces the recorded states exactly."""

import subprocess
import sys

import h5py
import numpy as np

from episodes.stages import replay_to_file

ARRAYS = ("qpos", "robot_qpos", "robot_qvel", "robot_qeffort", "object_pose", "action")


def _replay_in_subprocess(raw, out):
    code = ("import os; os.environ.setdefault('MUJOCO_GL','egl'); from pathlib import Path; "
            f"from episodes.stages import replay_to_file; replay_to_file(Path({str(raw)!r}), Path({str(out)!r}))")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_replay_twice_in_two_processes_is_byte_identical(raw_path, tmp_path):
    a, b = tmp_path / "a.replay.h5", tmp_path / "b.replay.h5"
    _replay_in_subprocess(raw_path, a)
    _replay_in_subprocess(raw_path, b)
    with h5py.File(a) as fa, h5py.File(b) as fb:
        for key in ARRAYS:
            assert fa[key][()].tobytes() == fb[key][()].tobytes(), key


def test_replay_reproduces_the_recording(raw_path, tmp_path):
    info = replay_to_file(raw_path, tmp_path / "r.replay.h5")
    assert info["fidelity"]["bit_exact"], info["fidelity"]
    assert info["fidelity"]["frames_over_bound"] == 0
    with h5py.File(tmp_path / "r.replay.h5") as f:
        assert f["qpos"].shape[0] == info["steps"] == 18
        assert np.isfinite(f["qpos"][()]).all()
