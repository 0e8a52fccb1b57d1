"""The bad-input corpus (corpus/bad_inputs.yaml): every case gives its expected message (issue 23, item 7)."""

from pathlib import Path

import h5py
import pytest
import yaml

from episodes.raw import raw_episode_id, read_raw
from episodes.reader import open_episode
from sim.errors import SpecError
from teleop.streams.arkit import PacketError, parse_packet

CORPUS = yaml.safe_load((Path(__file__).parent / "corpus" / "bad_inputs.yaml").read_text(encoding="utf-8"))
PER_STEP = ("action", "robot_qpos", "robot_qvel", "object_pose", "terminal", "stage_latched", "step_flags",
            "step_reasons")


def _cases(kind):
    return [pytest.param(case, id=case["id"]) for case in CORPUS[kind]]


def _rewrite(f: h5py.File, name: str, value) -> None:
    del f[name]
    f[name] = value


def _edit_hdf5(path: Path, case: dict) -> None:
    with h5py.File(path, "a") as f:
        if "set" in case:
            spec = case["set"]
            value = f[spec["dataset"]][()]
            value[tuple(spec["index"])] = spec["value"]
            f[spec["dataset"]][...] = value
        if "cast" in case:
            spec = case["cast"]
            value = f[spec["dataset"]][()]
            _rewrite(f, spec["dataset"], value.astype(str).astype(h5py.string_dtype()) if spec["dtype"] == "str"
                     else value.astype(spec["dtype"]))
        if "attr" in case:
            f.attrs[case["attr"]["name"]] = case["attr"]["value"]
        if "del_attr" in case:
            del f.attrs[case["del_attr"]]
        if "group" in case:
            del f[case["group"]]
            f.create_group(case["group"])
        if "steps" in case:
            for name in PER_STEP:
                _rewrite(f, name, f[name][: case["steps"]])
        if "del" in case:
            del f[case["del"]]
        if "flip_chunk" in case:
            ds = f[case["flip_chunk"]]
            info = ds.id.get_chunk_info(0)
            offset = info.byte_offset + info.size // 2
    if "flip_chunk" in case:
        with open(path, "r+b") as raw:
            raw.seek(offset)
            byte = raw.read(1)[0]
            raw.seek(offset)
            raw.write(bytes([byte ^ 0x10]))


def _damaged_copy(source: Path, case: dict, tmp_path: Path, default_name: str) -> Path:
    path = tmp_path / case.get("name", default_name)
    data = source.read_bytes()
    if "bytes" in case:
        data = case["bytes"].encode()
    elif "truncate" in case:
        data = data[: int(len(data) * case["truncate"])]
    path.write_bytes(data)
    if not ({"bytes", "truncate"} & case.keys()):
        _edit_hdf5(path, case)
    return path


@pytest.mark.parametrize("case", _cases("raw"))
def test_bad_raw_recordings(case, raw_path, tmp_path):
    path = _damaged_copy(raw_path, case, tmp_path, "episode_9000.raw.h5")
    with pytest.raises(SpecError) as err:
        raw_episode_id(path) if case.get("check") == "name" else read_raw(path)
    assert case["expect"] in str(err.value) and str(path) in str(err.value)


def _packet(case: dict) -> bytes:
    if "hex" in case:
        return bytes.fromhex(case["hex"])
    parts = case["packet"] if isinstance(case["packet"], list) else [case["packet"]]
    return "".join(p if isinstance(p, str) else p[0] * p[1] for p in parts).encode()


@pytest.mark.parametrize("case", _cases("arkit"))
def test_bad_arkit_datagrams(case):
    with pytest.raises(PacketError) as err:
        parse_packet(_packet(case))
    assert case["expect"] in str(err.value)


@pytest.mark.parametrize("case", _cases("episode"))
def test_bad_episodes(case, episode_dir, raw_path, tmp_path):
    source = raw_path if case.get("raw_instead") else episode_dir / "episode_0000.hdf5"
    path = _damaged_copy(source, case, tmp_path, "episode_0000.hdf5")
    with pytest.raises(SpecError) as err:
        with open_episode(path) as reader:
            for name in ("time/frame_index", *(f"cameras/{c}/rgb" for c in reader.camera_ids)):
                reader.read(name)
    assert case["expect"] in str(err.value) and str(path) in str(err.value)


def test_the_corpus_covers_each_kind():
    assert all(len(CORPUS[kind]) >= 4 for kind in ("raw", "arkit", "episode"))
    ids = [case["id"] for kind in CORPUS for case in CORPUS[kind]]
    assert len(set(ids)) == len(ids)
