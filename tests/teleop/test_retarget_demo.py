"""Raw recordings keep the operator stream behind their actions, and `b2d retarget` replays it onto
another embodiment: stored and read back, the same embodiment reproduces the actions bit for bit
(scripted person and a live session's bad stream alike), another one gives a raw recording that
replays and validates, twice the same bytes, and clear errors for recordings without a stream."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from b2d_cli.main import cli
from episodes.integrity import dataset_digests
from episodes.raw import STREAM, STREAM_FIELDS, read_raw, write_raw
from episodes.validate import validate_episode
from sim.errors import SpecError
from sim.registry import names, sensor_profile
from sim.replay import replay
from sim.scene.sample import demonstration_sample
from sim.tasks import load_task
from teleop.demos import record_demonstrations
from teleop.retarget_demo import retarget_file, retarget_recording
from teleop.scripted_stream import NOMINAL_PERIOD_NS
from teleop.session import TeleopSession
from teleop.session_driver import session_time_ns
from teleop.session_inputs import open_input
from test_teleop_session_streams import bad_stream, expected_flags

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"
OTHER = "xarm7_ability"
STEPS = 30


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """A short demonstration of the scripted person through the stream (the `b2d record` default)."""
    out = tmp_path_factory.mktemp("stream_demo")
    [r] = record_demonstrations(TASK, EMBODIMENT, 1, out, max_steps=STEPS)
    assert r.error is None, r.error
    return r.path


@pytest.fixture(scope="module")
def joint_demo(tmp_path_factory):
    """The direct joint path: no stream."""
    out = tmp_path_factory.mktemp("joint_demo")
    [r] = record_demonstrations(TASK, EMBODIMENT, 1, out, max_steps=3, operator="scripted")
    return r.path


def test_the_stream_is_stored_and_round_trips(demo, tmp_path):
    rec = read_raw(demo)
    s = rec.stream
    assert s is not None and s.num_steps == rec.num_steps == STEPS
    assert s.settings["nominal_period_ns"] == NOMINAL_PERIOD_NS and s.settings["translation_scale"] == 1.0
    assert s.settings["retarget"]["eta2"] == s.settings["retarget"]["eta1"]     # the scripted person's DexPilot
    assert s.arrived.all() and s.clock_known.all() and s.keypoints_valid.all() and s.wrist_valid.all()
    assert s.timestamp_ns.tolist() == [session_time_ns(k) for k in range(STEPS)] == s.clock_ns.tolist()
    assert np.isfinite(s.keypoints).all() and np.allclose(np.linalg.norm(s.wrist_quat, axis=2), 1.0)
    assert np.ptp(s.wrist_pos[:, 1], axis=0).max() > 0.02          # the right hand sets off: not a constant
    with h5py.File(demo, "r") as f:                               # digests cover the stream's datasets
        digests = dataset_digests(f)
    assert {f"{STREAM}/{k}" for k in STREAM_FIELDS} <= digests.keys()
    copy = write_raw(tmp_path / "episode_0000.raw.h5", rec)
    back = read_raw(copy).stream
    for key in STREAM_FIELDS:
        a, b = getattr(s, key), getattr(back, key)
        assert a.dtype == b.dtype and np.array_equal(a, b), key
    assert back.settings == s.settings


def test_recordings_without_a_stream_still_read(demo, joint_demo, tmp_path):
    assert read_raw(joint_demo).stream is None
    older = tmp_path / "episode_0000.raw.h5"
    older.write_bytes(demo.read_bytes())
    with h5py.File(older, "a") as f:            # as written before the stream was kept
        del f[STREAM]
    rec = read_raw(older)
    assert rec.stream is None and np.array_equal(rec.action, read_raw(demo).action)


@pytest.mark.parametrize("damage, field", [
    (lambda g: g.__delitem__("keypoints"), f"{STREAM}/keypoints"),
    (lambda g: (g.__delitem__("wrist_pos"), g.create_dataset("wrist_pos", data=np.zeros((STEPS, 3)))),
     f"{STREAM}/wrist_pos"),
    (lambda g: (g.__delitem__("arrived"), g.create_dataset("arrived", data=np.zeros(STEPS))), f"{STREAM}/arrived"),
    (lambda g: g.attrs.__delitem__("settings"), f"{STREAM}/settings"),
    (lambda g: g.attrs.__setitem__("settings", '{"nominal_period_ns": "fast"}'), f"{STREAM}/settings"),
    (lambda g: g.attrs.__setitem__("settings", "{not json"), f"{STREAM}/settings"),
])
def test_a_damaged_stream_names_the_file_and_field(demo, tmp_path, damage, field):
    bad = tmp_path / "episode_0000.raw.h5"
    bad.write_bytes(demo.read_bytes())
    with h5py.File(bad, "a") as f:
        damage(f[STREAM])
    with pytest.raises(SpecError, match=rf"{bad}: field '{field}': expected"):
        read_raw(bad)


def test_the_same_embodiment_reproduces_the_actions_bit_for_bit(demo):
    raw = read_raw(demo)
    again = retarget_recording(raw, EMBODIMENT, source=demo, hold_steps=0)
    assert again.num_steps == raw.num_steps and again.embodiment == EMBODIMENT
    for key in ("action", "robot_qpos", "robot_qvel", "object_pose", "step_flags", "stage_latched"):
        assert np.array_equal(getattr(again, key), getattr(raw, key)), key
    for key in STREAM_FIELDS:                      # its own stream is the one it was fed
        assert np.array_equal(getattr(again.stream, key), getattr(raw.stream, key)), key
    assert again.operator == "retarget:scripted:stream" and again.extra["retargeted_from"]["embodiment"] == EMBODIMENT


def test_a_live_session_with_bad_input_retargets_to_the_same_actions_and_flags(tmp_path):
    """Dropped, out-of-order, NaN and unreachable frames: the sanitizer decides the same way again."""
    session = TeleopSession(TASK, EMBODIMENT, open_input([f"recorded:{bad_stream(tmp_path / 'bad.npz')}"]),
                            tmp_path / "out", say=lambda m: None)
    session.handle("start")
    for _ in range(125):
        session.step()
    assert session.handle("save")[0]
    path = tmp_path / "out" / "episode_0000.raw.h5"
    raw = read_raw(path)
    assert {k: int(v) for k, v in enumerate(raw.step_flags) if v} == expected_flags()
    assert not raw.stream.arrived[list(range(50, 54))].any() and np.isnan(raw.stream.keypoints[100, 1]).any()
    again = retarget_recording(raw, EMBODIMENT, source=path, hold_steps=0)
    assert np.array_equal(again.action, raw.action) and np.array_equal(again.step_flags, raw.step_flags)
    assert again.step_reasons == raw.step_reasons


def test_another_embodiment_gives_a_raw_recording_that_replays_and_validates(demo, tmp_path):
    result = retarget_file(demo, OTHER, tmp_path / "retargeted", hold_steps=10)
    rec = read_raw(result.path)
    assert rec.embodiment == OTHER and rec.task == TASK and rec.num_steps == result.steps == STEPS + 10
    assert rec.scene_sample == read_raw(demo).scene_sample and rec.stream.num_steps == rec.num_steps
    assert rec.stream.arrived.all() and not rec.step_flags.any()
    assert rec.extra["episode_record"]["termination"] == "stream_end" and rec.extra["hold_steps"] == 10
    assert len(rec.actuator_names) == rec.action.shape[1] and rec.actuator_names != read_raw(demo).actuator_names
    assert replay(rec, result.path).fidelity["bit_exact"]
    from episodes.stages import raw_to_episode

    episode = raw_to_episode(result.path, sensor_profile("preview"), tmp_path / "episodes", max_frames=2)
    assert validate_episode(episode) == []


def test_world_wrists_follow_the_recorded_hand_base_and_replay_from_their_own_stream(demo, tmp_path):
    """--wrist world presets the anchors so that the new hand base starts where the recorded one was;
    they are kept in the stream settings, so the new recording reproduces itself bit for bit."""
    raw = read_raw(demo)
    rec = retarget_recording(raw, "panda_orca", source=demo, hold_steps=0, max_steps=12, wrist="world")
    anchors = rec.stream.settings["wrist_anchors"]
    assert set(anchors) == {"left", "right"} and rec.extra["wrist"] == "world"
    # the scripted person's wrist is the robot hand base in the world, so the panda's anchor sits at its own
    # home hand base: 10 cm further forward and 2 cm lower than the UR5's (sim/catalog/embodiments/)
    assert np.allclose(np.subtract(anchors["right"][:3], raw.stream.wrist_pos[0, 1]), [0, 0.1, -0.0185], atol=3e-3)
    path = write_raw(tmp_path / "episode_0000.raw.h5", rec)
    again = retarget_recording(read_raw(path), "panda_orca", source=path, hold_steps=0, wrist="session")
    assert np.array_equal(again.action, rec.action) and again.stream.settings == rec.stream.settings
    onward = retarget_recording(read_raw(path), EMBODIMENT, source=path, hold_steps=0, max_steps=3)
    assert "wrist_anchors" not in onward.stream.settings       # session wrists elsewhere: anchored on the first pose
    with h5py.File(path, "a") as f:
        f[STREAM].attrs["settings"] = f[STREAM].attrs["settings"].replace('"right": [', '"right": ["x", ')
    with pytest.raises(SpecError, match="wrist_anchors"):
        read_raw(path)


def test_retargeting_twice_gives_the_same_bytes(demo, tmp_path):
    a = retarget_file(demo, OTHER, tmp_path / "a", hold_steps=4, max_steps=20)
    b = retarget_file(demo, OTHER, tmp_path / "b", hold_steps=4, max_steps=20)
    assert a.steps == 20 and a.path.read_bytes() == b.path.read_bytes()


def test_a_recording_without_a_stream_is_refused_in_one_line(joint_demo, demo, tmp_path):
    with pytest.raises(SpecError, match="has none.*record one with `b2d record --operator stream`"):
        retarget_recording(read_raw(joint_demo), OTHER, source=joint_demo)
    alone = CliRunner().invoke(cli, ["retarget", str(joint_demo), "--embodiment", OTHER])
    assert alone.exit_code == 2 and len(alone.stderr.splitlines()) == 1 and alone.stdout == ""
    assert alone.stderr.startswith(f"error: {joint_demo}: field 'operator_stream': expected the operator stream")
    result = CliRunner().invoke(cli, ["retarget", str(joint_demo), str(demo), "--embodiment", EMBODIMENT,
                                      "--out", str(tmp_path), "--max-steps", "2"])
    assert result.exit_code == 2, result.output
    error = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert len(error) == 1 and str(joint_demo) in error[0] and "operator_stream" in error[0]
    assert "b2d teleop" in error[0]
    assert "success" in result.stdout and (tmp_path / "episode_0000.raw.h5").is_file()    # the other one ran


def test_unknown_embodiments_fail_fast_with_the_valid_ones(demo):
    result = CliRunner().invoke(cli, ["retarget", str(demo), "--embodiment", "ur5_hook"])
    assert result.exit_code == 2
    assert "unknown embodiment 'ur5_hook'" in result.stderr and all(n in result.stderr for n in names("embodiments"))


def test_the_cli_prints_the_verdict(demo, tmp_path):
    result = CliRunner().invoke(cli, ["retarget", str(demo), "--embodiment", OTHER, "--out", str(tmp_path),
                                      "--max-steps", "5", "--seed", "7"])
    assert result.exit_code == 0, result.output
    assert f"{OTHER} no success, stages 0/" in result.stdout and "steps=5" in result.stdout
    rec = read_raw(tmp_path / "episode_0000.raw.h5")
    assert rec.embodiment == OTHER and rec.seed == 7
    assert rec.scene_sample == demonstration_sample(load_task(TASK), 7).to_json() != read_raw(demo).scene_sample
