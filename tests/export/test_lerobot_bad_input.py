"""Bad input to `b2d export lerobot`: a clear error naming the file and field, the other episodes exported,
and an existing dataset never overwritten unless asked."""

import json
import shutil

import h5py
import pytest
from click.testing import CliRunner

from b2d_cli.main import cli
from lerobot_export import NothingExported, export_lerobot


@pytest.fixture
def without_view(export_episodes, tmp_path):
    """A copy of the first episode whose left_wrist camera is gone."""
    path = tmp_path / "episode_missing_view.hdf5"
    shutil.copy(export_episodes[0], path)
    with h5py.File(path, "r+") as f:
        del f["cameras/left_wrist"]
    return path


@pytest.fixture
def other_joints(export_episodes, tmp_path):
    """A copy of the second episode whose robot reports different joint names (another embodiment)."""
    path = tmp_path / "episode_other_robot.hdf5"
    shutil.copy(export_episodes[1], path)
    with h5py.File(path, "r+") as f:
        names = [f"other_{n.decode()}" for n in f["robot/joint_names"][()]]
        del f["robot/joint_names"]
        f.create_dataset("robot/joint_names", data=names, dtype=h5py.string_dtype())
    return path


def _info(root):
    return json.loads((root / "meta/info.json").read_text())


@pytest.mark.parametrize("version", ["v2.1", "v3.0"])
def test_bad_episodes_are_reported_and_the_rest_exported(export_episodes, without_view, tmp_path, version):
    not_episode = tmp_path / "notes.hdf5"
    not_episode.write_text("not an episode")
    inputs = [export_episodes[0], not_episode, without_view, export_episodes[1]]
    result = export_lerobot(inputs, tmp_path / "ds", version)
    assert result.episodes == export_episodes
    assert set(result.errors) == {str(not_episode), str(without_view)}
    assert "not HDF5" in result.errors[str(not_episode)]
    assert "cameras/left_wrist/rgb" in result.errors[str(without_view)]
    assert "left_wrist" in result.errors[str(without_view)] and "stereo_left" in result.errors[str(without_view)]
    info = _info(tmp_path / "ds")
    assert info["total_episodes"] == 2 and info["total_frames"] == result.frames
    assert not list((tmp_path / "ds").glob(".scratch"))


def test_an_episode_that_breaks_the_first_ones_layout_is_skipped(export_episodes, other_joints, tmp_path):
    result = export_lerobot([export_episodes[0], other_joints], tmp_path / "ds", "v3.0")
    assert result.episodes == export_episodes[:1]
    message = result.errors[str(other_joints)]
    assert "robot/joint_names" in message and export_episodes[0].name in message


def test_a_first_episode_without_a_chosen_view_is_skipped(export_episodes, without_view, tmp_path):
    views = ("left_wrist", "stereo_left")
    result = export_lerobot([without_view, export_episodes[1]], tmp_path / "ds", "v2.1", views=views)
    assert result.episodes == [export_episodes[1]] and list(result.errors) == [str(without_view)]
    features = _info(tmp_path / "ds")["features"]
    assert sorted(k for k, f in features.items() if f["dtype"] == "video") == [
        "observation.images.left_wrist", "observation.images.stereo_left"]
    assert (tmp_path / "ds/data/chunk-000/episode_000000.parquet").exists()


def test_nothing_exportable_writes_nothing(tmp_path):
    bad = tmp_path / "bad.hdf5"
    bad.write_bytes(b"\x89HDF\r\n")
    with pytest.raises(NothingExported, match="bad.hdf5"):
        export_lerobot([bad, tmp_path / "missing.hdf5"], tmp_path / "ds", "v3.0")
    assert not (tmp_path / "ds").exists()
    with pytest.raises(ValueError, match="valid formats: v2.1, v3.0"):
        export_lerobot([bad], tmp_path / "ds", "v4")


def test_an_existing_dataset_is_replaced_only_when_asked(export_episodes, tmp_path):
    out = tmp_path / "ds"
    out.mkdir()                                  # an empty folder is fine to fill
    export_lerobot(export_episodes[:1], out, "v2.1")
    with pytest.raises(FileExistsError, match="not empty"):
        export_lerobot(export_episodes, out, "v2.1")
    assert _info(out)["total_episodes"] == 1
    export_lerobot(export_episodes, out, "v3.0", overwrite=True)
    assert _info(out)["total_episodes"] == 2 and _info(out)["codebase_version"] == "v3.0"
    assert not (out / "meta/episodes.jsonl").exists()       # nothing left of the v2.1 export


def test_cli_exports_the_good_episodes_and_exits_1_for_the_bad(export_episodes, without_view, tmp_path):
    runner = CliRunner()
    args = ["export", "lerobot", str(export_episodes[0]), str(without_view), "--out", str(tmp_path / "ds"),
            "--format", "v3.0"]
    result = runner.invoke(cli, args)
    assert result.exit_code == 1, result.output
    assert "cameras/left_wrist/rgb" in result.output and "1 episode(s)" in result.output
    assert _info(tmp_path / "ds")["total_episodes"] == 1
    again = runner.invoke(cli, args)
    assert again.exit_code == 2 and "--overwrite" in again.output
