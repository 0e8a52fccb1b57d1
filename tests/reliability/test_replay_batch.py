"""`b2d replay RAW... --workers N` with several recordings: whole recordings on N processes (this one
included), each episode byte-identical to a one-worker replay, in the order given; an error met in a
spawned process comes back as the same error."""

import pickle

import h5py
import numpy as np
import pytest

from episodes.atomic import file_sha256
from episodes.replay_batch import longest_first, replay_recordings
from evaluation.errors import TaskSpecError
from sim.embodiment.fields import DescriptionError
from sim.errors import SpecError, UnknownNameError
from tactile.errors import TactileSpecError


@pytest.mark.parametrize("help_others", [True, False])
def test_whole_recordings_on_two_processes_give_the_one_worker_episodes(raw_dir, tiny_profile, tmp_path, help_others):
    raws = sorted(raw_dir.glob("*.raw.h5"))
    missing = tmp_path / "episode_0009.raw.h5"
    inputs = [raws[1], missing, raws[0]]
    one = list(replay_recordings(inputs, tiny_profile, tmp_path / "one", workers=1))
    shared = {}
    two = list(replay_recordings(inputs, tiny_profile, tmp_path / "two", workers=2, shared=shared,
                                 help_others=help_others))
    assert help_others or shared["frames_helped"] == 0      # without help, nobody renders for another
    assert [p for p, _ in two] == inputs
    for (_, a), (_, b) in zip(one, two):
        if isinstance(a, Exception):
            assert type(b) is type(a) and str(b) == str(a)
            assert "Traceback" in b.worker_traceback
        else:
            assert b.parent == tmp_path / "two" and b.name == a.name and file_sha256(b) == file_sha256(a)
    assert isinstance(two[1][1], SpecError) and str(missing) in str(two[1][1])


def test_the_projects_errors_cross_a_process_boundary_whole():
    errors = [SpecError("a.yaml", "x", "a number", [1]), SpecError(None, "x", "y"),
              UnknownNameError("task", "foo", ["b", "a"]), DescriptionError("arm.yaml: field 'q': bad"),
              DescriptionError("arm.yaml", "q", "a joint", 3), TactileSpecError("pad.yaml", "rows", "an int", "x"),
              TaskSpecError("metrics.stages[0]", "a predicate", 2, "task.yaml")]
    for error in errors:
        error.worker_traceback = "text"
        back = pickle.loads(pickle.dumps(error))
        assert type(back) is type(error) and str(back) == str(error) and back.__dict__ == error.__dict__


def test_a_batch_takes_the_longest_recordings_first_and_an_unreadable_one_last(tmp_path):
    """So that the batch's last, unshared work is a short recording's."""
    paths = []
    for name, steps in [("a", 5), ("b", 40), ("c", 5), ("d", 12)]:
        paths.append(tmp_path / f"{name}.raw.h5")
        with h5py.File(paths[-1], "w") as f:
            f.create_dataset("action", data=np.zeros((steps, 3)))
    bad = tmp_path / "bad.raw.h5"
    bad.write_bytes(b"not hdf5")
    items = list(enumerate([bad, *paths]))
    assert [p.name for _, p in longest_first(items)] == ["b.raw.h5", "d.raw.h5", "a.raw.h5", "c.raw.h5", "bad.raw.h5"]
