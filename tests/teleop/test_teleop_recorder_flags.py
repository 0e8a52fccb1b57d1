"""The online recorder keeps the operator stream's per-step flags and reasons: in memory, through the
raw file and back; operators without flags record 0 / "" as before; files written before the
reasons existed still read."""

from __future__ import annotations

import functools

import h5py
import numpy as np
import pytest

from episodes.raw import read_raw, write_raw
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from teleop.recorder import record_episode
from teleop.scripted_operator import ScriptedOperator
from teleop.session_driver import StreamOperator
from teleop.session_inputs import open_input
from teleop.streams import StepFlag
from test_teleop_session_streams import bad_stream, expected_flags

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"


@functools.lru_cache(maxsize=None)
def scene():
    return demonstration_scene(TASK, EMBODIMENT)


@pytest.fixture(scope="module")
def stream_recording(tmp_path_factory):
    path = bad_stream(tmp_path_factory.mktemp("stream") / "bad.npz")
    return record_episode(scene(), StreamOperator(open_input([f"recorded:{path}"])), "0000", 0)


def test_flags_and_reasons_of_a_stream_are_recorded_per_step(stream_recording):
    rec = stream_recording
    assert rec.operator == "teleop:recorded" and rec.step_flags.dtype == np.uint8
    assert rec.num_steps >= 190                        # the whole stream, bad frames and all
    flagged = {int(k): int(rec.step_flags[k]) for k in np.flatnonzero(rec.step_flags)}
    assert flagged == expected_flags()
    assert [bool(r) for r in rec.step_reasons] == [bool(f) for f in rec.step_flags]
    words = {StepFlag.DROPPED: "dropped", StepFlag.OUT_OF_ORDER: "out of order",
             StepFlag.BAD_KEYPOINTS: "non-finite", StepFlag.UNREACHABLE: "unreachable"}
    for step, bits in flagged.items():
        assert words[StepFlag(bits)] in rec.step_reasons[step]
    assert np.all(np.isfinite(rec.action))


def test_flags_and_reasons_survive_the_raw_file(stream_recording, tmp_path):
    back = read_raw(write_raw(tmp_path / "episode_0000.raw.h5", stream_recording))
    assert back.step_flags.tobytes() == stream_recording.step_flags.tobytes()
    assert back.step_reasons == stream_recording.step_reasons


def test_an_operator_without_flags_records_zero(tmp_path):
    rec = record_episode(scene(), ScriptedOperator(), "0000", 0, max_steps=6)
    assert rec.step_flags.tolist() == [0] * 6 and rec.step_reasons == [""] * 6
    assert read_raw(write_raw(tmp_path / "s.raw.h5", rec)).step_reasons == [""] * 6


def test_a_raw_file_written_before_reasons_existed_still_reads(stream_recording, tmp_path):
    path = write_raw(tmp_path / "old.raw.h5", stream_recording)
    with h5py.File(path, "a") as f:          # the layout before this change: no step_reasons
        del f["step_reasons"]
    old = read_raw(path)
    assert old.step_reasons == [""] * old.num_steps
    assert old.step_flags.tobytes() == stream_recording.step_flags.tobytes()


def test_reasons_of_the_wrong_length_name_the_field(stream_recording, tmp_path):
    path = write_raw(tmp_path / "bad.raw.h5", stream_recording)
    with h5py.File(path, "a") as f:
        del f["step_reasons"]
        f.create_dataset("step_reasons", data=np.array(["x"], dtype=h5py.string_dtype()))
    with pytest.raises(SpecError, match="step_reasons"):
        read_raw(path)
