"""`b2d teleop` end to end on generated stream files: bad input keeps the session alive and is
flagged in the saved recording; the same stream and script give the same arrays; clear errors;
`b2d bench retarget`."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from b2d_cli.main import cli
from episodes.raw import read_raw
from test_teleop_session_streams import bad_stream, expected_flags

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"
ARRAYS = ("initial_state", "action", "robot_qpos", "robot_qvel", "object_pose", "terminal", "stage_latched",
          "step_flags")


@pytest.fixture(scope="module")
def stream(tmp_path_factory):
    return bad_stream(tmp_path_factory.mktemp("stream") / "bad.npz")


def teleop(*args):
    return CliRunner().invoke(cli, ["teleop", "--task", TASK, "--embodiment", EMBODIMENT, *args])


def test_bad_input_is_flagged_in_the_saved_recording(stream, tmp_path):
    result = teleop("--input", f"recorded:{stream}", "--out", str(tmp_path), "--as-fast-as-possible",
                    "--script", "start;wait 3.0;save")
    assert result.exit_code == 0, result.output
    flags = expected_flags()
    assert f"0000  steps=180   no success  flagged={len(flags)}" in result.stdout
    rec = read_raw(tmp_path / "episode_0000.raw.h5")
    assert rec.operator == "teleop:recorded" and rec.num_steps == 180
    assert {int(k): int(rec.step_flags[k]) for k in np.flatnonzero(rec.step_flags)} == flags
    assert "unreachable" in rec.step_reasons[max(flags)] and np.all(np.isfinite(rec.action))
    assert rec.extra["input"] == f"recorded:{stream}"


def test_same_stream_and_script_give_identical_raw_arrays(stream, tmp_path):
    script = "wait 0.5;start;wait 1.5;save;start;wait 0.3;discard;start;wait 1.0;save"
    control_file = tmp_path / "session.ctl"
    control_file.write_text("# the same session as a file\n" + script.replace(";", "\n") + "\n")
    runs = []
    for i, control in enumerate((["--script", script], ["--control-file", str(control_file)])):
        out = tmp_path / f"run{i}"
        result = teleop("--input", f"recorded:{stream}", "--out", str(out), "--as-fast-as-possible", *control)
        assert result.exit_code == 0, result.output
        runs.append([read_raw(p) for p in sorted(out.glob("*.raw.h5"))])
    assert [r.episode_id for r in runs[0]] == [r.episode_id for r in runs[1]] == ["0000", "0001"]
    assert [r.num_steps for r in runs[0]] == [90, 60]
    assert runs[0][0].step_flags.any()                 # the first episode spans the stream's bad frames
    for a, b in zip(*runs):
        for key in ARRAYS:
            assert getattr(a, key).tobytes() == getattr(b, key).tobytes(), key
        assert a.step_reasons == b.step_reasons and a.scene_sample == b.scene_sample and a.seed == b.seed
    assert runs[0][0].action.tobytes() != runs[0][1].action.tobytes()


@pytest.mark.parametrize("args, words", [
    (["--task", "nope"], "valid task names"),
    (["--embodiment", "nope"], "valid embodiment names"),
])
def test_unknown_names_fail_fast_with_the_valid_ones(stream, args, words):
    base = {"--task": TASK, "--embodiment": EMBODIMENT}
    base.update(dict(zip(args[::2], args[1::2])))
    result = CliRunner().invoke(cli, ["teleop", *[x for kv in base.items() for x in kv], "--input",
                                      f"recorded:{stream}", "--script", "start"])
    assert result.exit_code == 2 and words in result.output


@pytest.mark.parametrize("args, words", [
    (["--input", "manus:", "--script", "start"], "Manus Core SDK"),
    (["--input", "webcam:/nonexistent/hand_landmarker.task", "--script", "start"], "model not found"),
    (["--input", "RECORDED", "--script", "start;jump"], "item 'jump'"),
    (["--input", "RECORDED"], "nothing can control the session"),
    (["--input", "arkit:0", "--script", "start", "--as-fast-as-possible"], "needs a recorded input"),
])
def test_bad_options_are_clear_errors(stream, tmp_path, args, words):
    args = [f"recorded:{stream}" if a == "RECORDED" else a for a in args]
    result = teleop(*args, "--out", str(tmp_path))
    assert result.exit_code == 2 and words in result.output, result.output
    assert not list(tmp_path.iterdir())


def test_a_refused_script_command_fails_the_run(stream, tmp_path):
    result = teleop("--input", f"recorded:{stream}", "--out", str(tmp_path), "--as-fast-as-possible",
                    "--script", "save;start;wait 0.2")
    assert result.exit_code == 1
    assert "script command refused: save at step 0: no episode to save" in result.output
    assert "episode 0000 was not saved (12 steps discarded)" in result.output
    assert not list(tmp_path.iterdir())


def test_bench_retarget_prints_figures_per_hand():
    result = CliRunner().invoke(cli, ["bench", "retarget", "--steps", "3"])
    assert result.exit_code == 0, result.output
    figures = json.loads(result.stdout)
    assert figures["frames"] == 3 and len(figures["hands"]) == 12
    assert all(f["ms_per_step"] > 0 and f["scipy_ms"] > 0 for f in figures["hands"].values())


def test_bench_teleop_prints_the_step_budget():
    result = CliRunner().invoke(cli, ["bench", "teleop", "--steps", "14"])
    assert result.exit_code == 0, result.output
    figures = json.loads(result.stdout)
    assert figures["steps"] == 14 and figures["flagged_steps"] == 2        # every 7th frame is missing
    assert figures["physics_ms"] > 0 and figures["recorder_ms"] > 0 and figures["command_ms"] > 0
