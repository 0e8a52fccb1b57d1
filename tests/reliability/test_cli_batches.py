"""Issue 23, items 2 and 4: every command error is one line naming the input and the fault; a batch goes
on past bad inputs and ends with a summary; outputs never overwrite each other silently; inputs
outside the expected naming are refused."""

import h5py
import pytest
from click.testing import CliRunner

from b2d_cli.main import cli
from episodes.atomic import file_sha256


def _invoke(*args):
    return CliRunner().invoke(cli, [str(a) for a in args])


def _error_lines(output: str) -> list[str]:
    return [line for line in output.splitlines() if line.startswith("error: ")]


@pytest.mark.parametrize("workers", [1, 2])    # 2: whole recordings on two processes, errors passed back
def test_a_replay_batch_goes_on_past_bad_inputs_and_refuses_to_overwrite(raw_path, tmp_path, workers):
    other = tmp_path / "other" / raw_path.name            # same name, another recording
    other.parent.mkdir()
    other.write_bytes(raw_path.read_bytes())
    with h5py.File(other, "a") as f:
        f.attrs["seed"] = 12345
    foreign = tmp_path / "notes.raw.h5"
    foreign.write_bytes(raw_path.read_bytes())
    truncated = tmp_path / "episode_0007.raw.h5"
    truncated.write_bytes(raw_path.read_bytes()[:2000])
    missing = tmp_path / "episode_0008.raw.h5"
    out = tmp_path / "out"

    result = _invoke("replay", raw_path, other, foreign, truncated, missing, "--profile", "preview",
                     "--out", out, "--max-frames", 1, "--workers", workers)
    assert result.exit_code == 2, result.output
    errors = _error_lines(result.output)
    assert len(errors) == 4, result.output
    assert f"{out / 'episode_0000.hdf5'}: field 'meta/dataset'" in errors[0] and str(other) in errors[0]
    assert f"{foreign}: field '<file name>'" in errors[1] and "episode_<digits>.raw.h5" in errors[1]
    assert f"{truncated}: field '<file>'" in errors[2] and "truncated" in errors[2]
    assert f"{missing}: field '<file>': expected an existing raw recording file" in errors[3]
    assert "4 of 5 recordings failed:" in result.output
    # the good input's episode was written, listed, and not replaced by the other recording's
    episode = out / "episode_0000.hdf5"
    with h5py.File(episode) as f:
        assert file_sha256(raw_path) in f["meta/dataset"][()].decode()
    assert _invoke("validate", episode).exit_code == 0

    # replaying the same recording again is a re-run: it replaces its own episode
    again = _invoke("replay", raw_path, "--profile", "preview", "--out", out, "--max-frames", 1)
    assert again.exit_code == 0, again.output


def test_an_existing_corrupt_episode_in_the_output_folder_is_refused_not_a_traceback(raw_path, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "episode_0000.hdf5").write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 100)
    result = _invoke("replay", raw_path, "--profile", "preview", "--out", out, "--max-frames", 1)
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert f"{out / 'episode_0000.hdf5'}: field '<file>'" in _error_lines(result.output)[0]


def test_validate_checks_every_file_and_lists_the_invalid_ones(episode_dir, tmp_path):
    good = episode_dir / "episode_0000.hdf5"
    junk = tmp_path / "junk.hdf5"
    junk.write_bytes(b"not hdf5")
    result = _invoke("validate", junk, tmp_path / "missing.hdf5", good)
    assert result.exit_code == 1
    assert f"{junk}: INVALID" in result.output and f"{junk}: <file>: not a readable HDF5 file" in result.output
    assert f"{tmp_path / 'missing.hdf5'}: <file>: no such file" in result.output
    assert f"{good}: ok" in result.output
    assert f"2 of 3 episodes invalid: {junk}, {tmp_path / 'missing.hdf5'}" in result.output


def test_refused_values_exit_2():
    for args in (["record", "--task", "citrus_plate_loading", "--embodiment", "ur5_rh5dg2", "--out", "x",
                  "--max-steps", "0"],
                 ["replay", "x.raw.h5", "--out", "x", "--max-frames", "-1"]):
        result = _invoke(*args)
        assert result.exit_code == 2 and "is not in the range x>=1" in result.output


def test_any_other_error_is_one_line_with_its_kind(monkeypatch, tmp_path):
    """Errors that are not b2d's own (a library's, the machine's) end as one line too, not a traceback."""
    from sim import registry

    def broken(name):
        raise RuntimeError("the catalog folder is not readable")

    monkeypatch.setattr(registry, "sensor_profile", broken)
    result = _invoke("replay", tmp_path / "episode_0000.raw.h5", "--out", tmp_path)
    assert result.exit_code == 1
    assert _error_lines(result.output) == ["error: RuntimeError: the catalog folder is not readable"]
