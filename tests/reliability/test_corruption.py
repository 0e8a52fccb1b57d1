"""Issue 23, item 3: a flipped byte anywhere in an episode's data, or a deleted group, is reported by
`b2d validate` and by the asset check, naming the file and the dataset."""

import json

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from b2d_cli.main import cli
from b2d_pipeline.checks import episode_problems
from episodes.manifest import write_manifest
from episodes.validate import validate_episode


def _flip(path, offset: int, bit: int = 0) -> None:
    with open(path, "r+b") as f:
        f.seek(offset)
        byte = f.read(1)[0]
        f.seek(offset)
        f.write(bytes([byte ^ (1 << bit)]))


def _chunk_offset(path, dataset: str, frame: int = 0) -> int:
    """File offset of the middle of one stored chunk of `dataset`."""
    with h5py.File(path) as f:
        ds = f[dataset]
        if ds.chunks is None:
            return ds.id.get_offset() + ds.id.get_storage_size() // 2
        info = ds.id.get_chunk_info_by_coord((frame,) + (0,) * (ds.ndim - 1))
        return info.byte_offset + info.size // 2


def _validate(path) -> tuple[int, str]:
    result = CliRunner().invoke(cli, ["validate", str(path)])
    return result.exit_code, result.output


@pytest.mark.parametrize("dataset", [
    "cameras/chest/rgb",                         # an image chunk (Zstd)
    "cameras/chest/depth_m",                     # a float image chunk (Blosc LZ4: no checksum of its own)
    "action/action",                             # a per-frame value chunk (Zstd, 256 frames)
    "cameras/chest/intrinsic",                   # an uncompressed static dataset: decodes, but differs
])
def test_a_flipped_byte_names_the_file_and_the_dataset(episode_copy, dataset):
    assert validate_episode(episode_copy) == []
    _flip(episode_copy, _chunk_offset(episode_copy, dataset), bit=3)
    code, out = _validate(episode_copy)
    assert code == 1 and "INVALID" in out
    assert f"{episode_copy}: {dataset}:" in out, out


def test_a_flipped_image_chunk_is_found_by_decoding_even_without_a_manifest(episode_copy):
    (episode_copy.parent / "episode_manifest.json").unlink()
    _flip(episode_copy, _chunk_offset(episode_copy, "cameras/chest/rgb", frame=3), bit=5)
    problems = validate_episode(episode_copy)
    assert any(p.startswith("cameras/chest/rgb: frames 3-3 cannot be decoded") for p in problems), problems


def test_a_deleted_object_group_is_reported(episode_copy):
    with h5py.File(episode_copy, "a") as f:
        del f["objects/lemon_1"]
    code, out = _validate(episode_copy)
    assert code == 1
    assert f"{episode_copy}: objects/lemon_1: missing (meta/scene places the object 'lemon_1')" in out
    assert f"{episode_copy}: objects/lemon_1/pose_world: missing (listed in episode_manifest.json)" in out


def test_the_asset_check_reports_corruption_and_files_gone(episode_copy):
    folder = episode_copy.parent
    assert episode_problems([folder]) == (1, {})
    _flip(episode_copy, _chunk_offset(episode_copy, "robot/qpos"))
    checked, problems = episode_problems([folder])
    assert checked == 1 and any(p.startswith("robot/qpos: ") for p in problems[str(episode_copy)])
    episode_copy.unlink()
    assert episode_problems([folder])[1] == {str(episode_copy): ["<file>: missing (listed in episode_manifest.json)"]}


def test_rewriting_the_manifest_keeps_what_was_recorded(episode_copy):
    """Updating the manifest for other files must not bless a file corrupted since it was written."""
    folder = episode_copy.parent
    _flip(episode_copy, _chunk_offset(episode_copy, "robot/qvel"))
    write_manifest(folder, updated=[])
    assert any(p.startswith("robot/qvel: stored bytes differ") for p in validate_episode(episode_copy))
    (folder / "episode_0001.hdf5").write_bytes(b"not hdf5")      # an unreadable file is left out, not fatal
    write_manifest(folder, updated=[folder / "episode_0001.hdf5"])
    files = [e["file"] for e in json.loads((folder / "episode_manifest.json").read_text())["episodes"]]
    assert files == ["episode_0000.hdf5"]


def test_random_flips_are_all_reported_with_a_manifest(episode_copy, tmp_path):
    """The campaign's random flips, a few of them: every one is reported."""
    data = episode_copy.read_bytes()
    rng = np.random.default_rng(23)
    for offset in rng.integers(0, len(data), 6):
        damaged = bytearray(data)
        damaged[offset] ^= 1 << int(rng.integers(8))
        episode_copy.write_bytes(bytes(damaged))
        assert validate_episode(episode_copy), f"flip at byte {offset} not reported"
