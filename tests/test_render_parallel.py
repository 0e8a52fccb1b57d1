"""Rendering split over processes gives the same arrays as one process; episodes of tasks with
articulated objects carry the joint states (schema b2d.episode/2)."""

import json

import h5py
import numpy as np
import pytest

from episodes import stages
from episodes.h5_concat import concat_frames
from episodes.raw import write_raw
from episodes.render_pool import shared_helpers
from episodes.stages import assemble_episode, render_to_file, replay_to_file
from episodes.validate import validate_episode
from episodes.writer import EpisodeWriter
from sim.registry import parse_sensor_profile
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample
from sim.tasks import load_task
from teleop.recorder import record_episode

from held_frames import held_until_helpers_take
from tiny_profile import TINY


def _arrays(path) -> dict[str, bytes]:
    """Every dataset's content as bytes (strings by their repr)."""
    out = {}

    def grab(name, obj):
        if isinstance(obj, h5py.Dataset):
            value = obj[()]
            out[name] = value.tobytes() if isinstance(value, np.ndarray) and value.dtype.kind != "O" else repr(value).encode()

    with h5py.File(path) as f:
        f.visititems(grab)
    return out


def test_two_workers_render_the_same_arrays_as_one(replay_path, tmp_path, monkeypatch):
    profile = parse_sensor_profile(TINY)
    one = render_to_file(replay_path, profile, tmp_path / "one.render.h5", workers=1)
    shared_helpers(1)       # up before the render: one that is still starting is not waited for, takes no frame
    # the writer waits for the helper's first frames (tiny frames render faster than its scene is built)
    monkeypatch.setattr(stages, "ReplayFrames", held_until_helpers_take(lambda: shared_helpers(1)))
    two = render_to_file(replay_path, profile, tmp_path / "two.render.h5", workers=2)
    assert (one["workers"], two["workers"]) == (1, 2)
    assert one["frames"] == two["frames"] == 18
    # issue 22: each worker's frames and set-up are timed for the bench
    assert len(one["frame_windows"]) == 1 and len(two["frame_windows"]) == 2 and two["setup_cpu_s"] > 0
    a, b = _arrays(tmp_path / "one.render.h5"), _arrays(tmp_path / "two.render.h5")
    assert a.keys() == b.keys()
    assert "cameras/chest/rgb" in a and "robot/tactile/tacmap/right_index_tip" in a
    differing = [k for k in a if a[k] != b[k]]
    assert not differing


def test_concat_rejects_parts_with_different_datasets(tmp_path):
    with EpisodeWriter(tmp_path / "a.h5", {}) as w:
        w.append({"x": np.zeros(3)})
    with EpisodeWriter(tmp_path / "b.h5", {}) as w:
        w.append({"y": np.zeros(3)})
    with pytest.raises(ValueError, match="b.h5"):
        concat_frames([tmp_path / "a.h5", tmp_path / "b.h5"], tmp_path / "out.h5")
    assert not (tmp_path / "out.h5").exists()


def test_concat_rejects_parts_whose_frames_differ_in_dtype(tmp_path):
    """Image chunks are copied as raw bytes, so a part with another dtype must not be joined."""
    for name, dtype in (("a.h5", np.float32), ("b.h5", np.float64)):
        with EpisodeWriter(tmp_path / name, {}) as w:
            w.append({"img": np.ones((32, 32), dtype)})
    with pytest.raises(ValueError, match=r"b.h5: dtype or frame shape differs .*'img'"):
        concat_frames([tmp_path / "a.h5", tmp_path / "b.h5"], tmp_path / "out.h5")
    assert not (tmp_path / "out.h5").exists()


class _HoldHome:
    """An operator that keeps the robot at home: the door's joint state is still recorded."""
    name = "hold_home"

    def reset(self, scene, data):
        self.ctrl = scene.layout.home_ctrl

    def act(self, step, data):
        return self.ctrl

    def done(self, step):
        return False


def test_articulated_joint_states_and_distractors_reach_the_episode(tmp_path):
    spec = load_task("microwave_bowl_loading")
    scene = build_scene(spec, spec.paper_embodiment, demonstration_sample(spec, 7))
    raw = write_raw(tmp_path / "episode_0000.raw.h5", record_episode(scene, _HoldHome(), "0000", 7, max_steps=6))
    profile = parse_sensor_profile({**TINY, "tactile": {"enabled": False}})
    replay_to_file(raw, tmp_path / "r.h5")
    render_to_file(tmp_path / "r.h5", profile, tmp_path / "v.h5")
    episode = tmp_path / "episode_0000.hdf5"
    assemble_episode(tmp_path / "r.h5", tmp_path / "v.h5", profile, episode)
    assert validate_episode(episode) == []
    with h5py.File(episode) as f:
        names = [n.decode() for n in f["objects/microwave/joint_names"][()]]
        assert names == [j for j in scene.joint_names if j.startswith("microwave/")] and names
        assert f["objects/microwave/qpos"].shape == (6, len(names))
        door = names.index("microwave/door")
        assert np.allclose(f["objects/microwave/qpos"][:, door], scene.joint_initial["microwave/door"], atol=1e-3)
        assert {f"objects/{d}/pose_world" for d in scene.distractor_names} <= set(_arrays(episode))
    # a missing articulated node is reported by name
    with h5py.File(episode, "a") as f:
        del f["objects/microwave/qvel"]
    assert any("objects/microwave/qvel: missing" in p for p in validate_episode(episode))


def test_frames_drifting_from_the_recording_are_flagged_not_dropped(raw_path, tmp_path):
    from episodes.stages import raw_to_episode

    edited = tmp_path / "episode_0009.raw.h5"
    edited.write_bytes(raw_path.read_bytes())
    with h5py.File(edited, "a") as f:      # the recording claims lemon_1 was 2 cm higher from step 9 on
        f["object_pose"][9:, 0, 2] += 0.02
    profile = parse_sensor_profile({**TINY, "tactile": {"enabled": False}})
    episode = raw_to_episode(edited, profile, tmp_path / "out", drift_bound_m=0.01)
    with h5py.File(episode) as f:
        valid = f["frame_valid"][()]
        errors = [e.decode() for e in f["frame_errors"][()]]
        steps = f["time/sim_step"][()] - 1
        fidelity = json.loads(f["meta/replay_fidelity"][()])
    assert valid.size == 18 and np.array_equal(valid, steps < 9)
    assert all("replay drift beyond bound" in e for e, s in zip(errors, steps) if s >= 9)
    assert fidelity["frames_over_bound"] == 9 and fidelity["drift_bound_m"] == 0.01
    assert not fidelity["bit_exact"]


def test_rendering_works_when_mujoco_was_imported_before_any_gl_default(tmp_path):
    """The CLI imports mujoco before sim.offscreen could set MUJOCO_GL; rendering must still go headless."""
    import os
    import subprocess
    import sys

    code = ("import mujoco, numpy as np\n"
            "m = mujoco.MjModel.from_xml_string('<mujoco><worldbody><light pos=\"0 0 2\"/><camera name=\"c\" pos=\"0 0 1\"/>"
            "<geom size=\"0.1\"/></worldbody></mujoco>')\n"
            "d = mujoco.MjData(m); mujoco.mj_forward(m, d)\n"
            "from sim.offscreen import OffscreenRenderer\n"
            "r = OffscreenRenderer(m, 32, 24); r.update(d, 0)\n"
            "depth, ids = r.depth_and_geoms(True)\n"
            "print(round(float(depth[12, 16]), 3), int(ids[12, 16]))\n")
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM", "DISPLAY")}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    depth, geom = out.stdout.split()
    assert abs(float(depth) - 0.9) < 0.01 and geom == "0"    # camera 1 m above a 0.1 m sphere at the origin


def test_operator_stream_flags_reach_the_episode_per_frame(raw_path, tmp_path):
    from episodes.stages import raw_to_episode

    edited = tmp_path / "episode_0008.raw.h5"
    edited.write_bytes(raw_path.read_bytes())
    with h5py.File(edited, "a") as f:      # steps 4 and 5 had a dropped frame and NaN keypoints
        f["step_flags"][4], f["step_flags"][5] = 1, 4
        reasons = ["" for _ in range(f["step_flags"].shape[0])]
        reasons[4], reasons[5] = "dropped frame", "nan keypoints\ndropped frame"
        if "step_reasons" in f:
            del f["step_reasons"]
        f.create_dataset("step_reasons", data=reasons, dtype=h5py.string_dtype())
    profile = parse_sensor_profile({**TINY, "rate_hz": 20, "tactile": {"enabled": False}})   # a frame per 3 steps
    episode = raw_to_episode(edited, profile, tmp_path / "out")
    with h5py.File(episode) as f:
        flags = f["action/stream_flags"][()]
        reasons = [r.decode() for r in f["action/stream_reasons"][()]]
    assert flags.tolist() == [0, 5, 0, 0, 0, 0]          # frame 1 covers steps 3..5
    assert reasons[1] == "dropped frame\nnan keypoints" and reasons[0] == ""
    assert validate_episode(episode) == []


def test_the_hand_model_is_recorded_and_replay_rebuilds_it(raw_path, tmp_path, monkeypatch):
    """B2D_HAND_MODEL only chooses what a new recording is built with; replay follows the recording."""
    from episodes.raw import read_raw
    from episodes.stages import raw_to_episode

    assert read_raw(raw_path).hand_model == "generated"
    monkeypatch.setenv("B2D_HAND_MODEL", "real")      # citrus' rh5dg2 has no real model: must not be asked for
    profile = parse_sensor_profile({**TINY, "tactile": {"enabled": False}})
    episode = raw_to_episode(raw_path, profile, tmp_path / "out", max_frames=2)
    with h5py.File(episode) as f:
        assert json.loads(f["meta/collection_config"][()])["hand_model"] == "generated"


def test_side_by_side_ceiling_renders_the_same_file_in_each_process(replay_path, tmp_path):
    """`b2d bench replay --workers N` measures what the cores allow: N independent whole renders at once
    against one alone; each process's file is the one-worker file."""
    from b2d_cli.render_workers_bench import side_by_side_figures

    out = side_by_side_figures(replay_path, parse_sensor_profile(TINY), 2, tmp_path, repeats=1)
    assert out["render_files_identical"] is True
    assert len(out["wall_s_alone"]) == len(out["wall_s_together"]) == 1
    assert out["ceiling_speedup"] == pytest.approx(2 / out["together_vs_alone"], rel=0.01)
    one = render_to_file(replay_path, parse_sensor_profile(TINY), tmp_path / "one.render.h5")
    assert one["frames"] == 18
    assert _arrays(tmp_path / "one.render.h5") == _arrays(tmp_path / "side_1.render.h5")
