"""Bad raw recordings fail with the file and the field; nothing half-written is left behind."""

import h5py
import numpy as np
import pytest

from episodes.raw import read_raw
from episodes.stages import raw_to_episode
from sim.errors import SpecError, UnknownNameError
from sim.registry import sensor_profile


def _copy(raw_path, tmp_path, name="episode_9000.raw.h5"):
    out = tmp_path / name
    out.write_bytes(raw_path.read_bytes())
    return out


def test_truncated_recording(raw_path, tmp_path):
    bad = _copy(raw_path, tmp_path)
    bad.write_bytes(bad.read_bytes()[: bad.stat().st_size // 2])
    with pytest.raises(SpecError) as err:
        read_raw(bad)
    assert str(bad) in str(err.value) and "truncated" in str(err.value)


def test_nan_action_names_step_and_actuator(raw_path, tmp_path):
    bad = _copy(raw_path, tmp_path)
    with h5py.File(bad, "a") as f:
        action = f["action"][()]
        action[5, 2] = np.nan
        f["action"][...] = action
    with pytest.raises(SpecError) as err:
        read_raw(bad)
    assert err.value.field == "action" and "step 5" in str(err.value) and str(bad) in str(err.value)


def test_wrong_joint_count(raw_path, tmp_path):
    bad = _copy(raw_path, tmp_path)
    with h5py.File(bad, "a") as f:
        action = f["action"][()][:, :-1]
        del f["action"]
        f["action"] = action
    with pytest.raises(SpecError) as err:
        read_raw(bad)
    assert err.value.field == "action" and "shape" in str(err.value)


def test_unknown_task_fails_and_leaves_no_episode(raw_path, tmp_path):
    bad = _copy(raw_path, tmp_path)
    with h5py.File(bad, "a") as f:
        f.attrs["task"] = "juggling"
    out = tmp_path / "episodes"
    with pytest.raises(UnknownNameError) as err:
        raw_to_episode(bad, sensor_profile("preview"), out)
    assert "citrus_plate_loading" in str(err.value)
    assert not list(out.rglob("*.hdf5")) and not list(out.rglob("*.tmp-*"))
