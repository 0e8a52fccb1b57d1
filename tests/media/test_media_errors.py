"""Bad input to `b2d export usd` / `b2d show`: one clear line naming the file and the field, exit 2."""

import pytest
from click.testing import CliRunner

from b2d_cli.main import cli

COMMANDS = (["export", "usd"], ["show"])


@pytest.mark.parametrize("command", COMMANDS)
def test_a_missing_file_is_named(command, tmp_path):
    path = tmp_path / "nope.hdf5"
    result = CliRunner().invoke(cli, [*command, str(path), "--out", str(tmp_path / "o.png")])
    assert result.exit_code == 2
    assert str(path) in result.stderr and "'<file>'" in result.stderr


@pytest.mark.parametrize("command", COMMANDS)
def test_a_file_that_is_not_hdf5_is_named(command, tmp_path):
    path = tmp_path / "episode_text.hdf5"
    path.write_text("not an episode")
    result = CliRunner().invoke(cli, [*command, str(path), "--out", str(tmp_path / "o.png")])
    assert result.exit_code == 2 and str(path) in result.stderr and "not HDF5" in result.stderr


@pytest.mark.parametrize("command", COMMANDS)
def test_a_raw_recording_is_not_an_episode(command, raw_path, tmp_path):
    result = CliRunner().invoke(cli, [*command, str(raw_path), "--out", str(tmp_path / "o.png")])
    assert result.exit_code == 2
    assert str(raw_path) in result.stderr and "meta/schema_version" in result.stderr


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("frames", ["2:9", "3:", "2:1", "a:b", "1"])
def test_a_frame_range_outside_the_episode_is_named(command, frames, tiny_episode, tmp_path):
    result = CliRunner().invoke(cli, [*command, str(tiny_episode), "--frames", frames,
                                      "--out", str(tmp_path / "o.png")])
    assert result.exit_code == 2
    assert str(tiny_episode) in result.stderr and "'--frames'" in result.stderr
    assert list(tmp_path.iterdir()) == []


def test_show_names_an_unknown_output_kind(tiny_episode, tmp_path):
    result = CliRunner().invoke(cli, ["show", str(tiny_episode), "--out", str(tmp_path / "o.gif")])
    assert result.exit_code == 2 and "'--out'" in result.stderr and ".mp4" in result.stderr


def test_show_names_a_missing_camera_dataset(tiny_episode, tmp_path):
    import h5py

    broken = tmp_path / "episode_broken.hdf5"
    broken.write_bytes(tiny_episode.read_bytes())
    with h5py.File(broken, "a") as f:
        del f["episode/success"]
    result = CliRunner().invoke(cli, ["show", str(broken), "--out", str(tmp_path / "o.png")])
    assert result.exit_code == 2 and str(broken) in result.stderr and "episode/success" in result.stderr
