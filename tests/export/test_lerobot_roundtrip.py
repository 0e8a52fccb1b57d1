"""An export read back with pyarrow and PyAV matches the HDF5 episodes frame by frame, in both formats."""

import io
import json
from pathlib import Path

import av
import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from PIL import Image

from episodes.reader import open_episode
from lerobot_export import export_lerobot

VIDEO_TOLERANCE = 8.0    # mean absolute difference per frame, 0-255 scale (measured about 3.5 at CRF 18)


def _decode(mp4: Path) -> list[tuple[float, np.ndarray]]:
    with av.open(str(mp4)) as container:
        return [(float(f.time), f.to_ndarray(format="rgb24")) for f in container.decode(video=0)]


def read_back(root: Path) -> tuple[dict, list[dict]]:
    """info.json and, per episode: its task, its frame table and {video key: (mp4, from_timestamp)}."""
    info = json.loads((root / "meta/info.json").read_text())
    video_keys = [k for k, f in info["features"].items() if f["dtype"] == "video"]
    episodes = []
    if info["codebase_version"] == "v2.1":
        lines = (root / "meta/tasks.jsonl").read_text().splitlines()
        tasks = {t["task_index"]: t["task"] for t in map(json.loads, lines)}
        for row in map(json.loads, (root / "meta/episodes.jsonl").read_text().splitlines()):
            i, chunk = row["episode_index"], row["episode_index"] // info["chunks_size"]
            table = pq.read_table(root / info["data_path"].format(episode_chunk=chunk, episode_index=i))
            videos = {k: (root / info["video_path"].format(episode_chunk=chunk, video_key=k, episode_index=i), 0.0)
                      for k in video_keys}
            episodes.append({"tasks": row["tasks"], "table": table, "videos": videos, "task_names": tasks})
    else:
        tasks = pd.read_parquet(root / "meta/tasks.parquet")
        task_names = {int(i): t for t, i in zip(tasks.index, tasks["task_index"])}
        rows = pq.read_table(next((root / "meta/episodes").glob("*/*.parquet"))).to_pylist()
        # as lerobot does: every data file in order makes one table that dataset_from_index points into
        data = pa.concat_tables(pq.read_table(p) for p in sorted((root / "data").glob("*/*.parquet")))
        for row in rows:
            table = data.slice(row["dataset_from_index"], row["length"])
            own_file = pq.read_table(root / info["data_path"].format(chunk_index=row["data/chunk_index"],
                                                                     file_index=row["data/file_index"]))
            assert row["episode_index"] in own_file.column("episode_index").to_pylist()
            videos = {k: (root / info["video_path"].format(video_key=k, chunk_index=row[f"videos/{k}/chunk_index"],
                                                           file_index=row[f"videos/{k}/file_index"]),
                          row[f"videos/{k}/from_timestamp"]) for k in video_keys}
            episodes.append({"tasks": row["tasks"], "table": table, "videos": videos, "task_names": task_names})
    return info, episodes


def _column(table, key) -> np.ndarray:
    return np.asarray(table.column(key).to_pylist())


ONE_EPISODE_PER_FILE = {"data_mb": 1e-9, "video_mb": 1e-9}   # v3.0 starts a new file once one passes its limit


@pytest.mark.parametrize("version, limits", [("v2.1", {}), ("v3.0", {}), ("v3.0", ONE_EPISODE_PER_FILE)],
                         ids=["v2.1", "v3.0", "v3.0-file-per-episode"])
def test_every_frame_matches_the_hdf5_episode(export_episodes, tmp_path, version, limits):
    result = export_lerobot(export_episodes, tmp_path / "ds", version, **limits)
    assert result.errors == {} and result.episodes == export_episodes
    info, episodes = read_back(tmp_path / "ds")
    assert info["codebase_version"] == version and info["total_episodes"] == len(export_episodes)
    if limits:
        assert len(list((tmp_path / "ds/data").glob("*/*.parquet"))) == len(export_episodes)
    fps = info["fps"]
    first_index, states = 0, []
    for e, (path, exported) in enumerate(zip(export_episodes, episodes)):
        table = exported["table"]
        with open_episode(path) as reader:
            frames = reader.num_frames
            assert table.num_rows == frames
            # state and action: the HDF5 values as float32, bit for bit
            for key, source in (("observation.state", "robot/qpos"), ("observation.velocity", "robot/qvel"),
                                ("observation.effort", "robot/qeffort"), ("action", "action/action")):
                np.testing.assert_array_equal(_column(table, key).astype(np.float32),
                                              reader.read(source).astype(np.float32), err_msg=f"{path} {key}")
            assert info["features"]["observation.state"]["names"] == reader.static("robot/joint_names")
            assert info["features"]["action"]["names"] == reader.static("action/names")
            np.testing.assert_array_equal(_column(table, "next.done"), reader.read("episode/done"))
            np.testing.assert_array_equal(_column(table, "frame_index"), np.arange(frames))
            np.testing.assert_array_equal(_column(table, "episode_index"), np.full(frames, e))
            np.testing.assert_array_equal(_column(table, "index"), first_index + np.arange(frames))
            np.testing.assert_array_equal(_column(table, "timestamp"), (np.arange(frames) / fps).astype(np.float32))
            task = exported["task_names"][int(_column(table, "task_index")[0])]
            assert task == reader.meta("instruction") == exported["tasks"][0]
            # tactile: each site's TacMap, lossless
            assert reader.tactile_sites
            for site in reader.tactile_sites:
                images = [np.asarray(Image.open(io.BytesIO(cell["bytes"])))
                          for cell in table.column(f"observation.tactile.{site}").to_pylist()]
                np.testing.assert_array_equal(np.stack(images), reader.read(f"robot/tactile/tacmap/{site}"))
            # every view: one decoded frame per stored frame, at its timestamp, within codec tolerance
            assert len(exported["videos"]) == len(reader.camera_ids) == 4
            for key, (mp4, start) in exported["videos"].items():
                # v3.0 joins the episodes of a file: each starts where the one before ended
                joined = version == "v3.0" and not limits
                assert start == pytest.approx(first_index / fps if joined else 0.0)
                assert len(_decode(mp4)) == (result.frames if joined else frames)
                rgb = reader.read(f"cameras/{key.removeprefix('observation.images.')}/rgb")
                decoded = [(round((t - start) * fps), image) for t, image in _decode(mp4)
                           if start - 0.5 / fps <= t < start + (frames - 0.5) / fps]
                assert [k for k, _ in decoded] == list(range(frames)), key
                for k, image in decoded:
                    diff = np.abs(image.astype(np.int16) - rgb[k].astype(np.int16)).mean()
                    assert diff < VIDEO_TOLERANCE, (key, k, diff)
            states.append(reader.read("robot/qpos").astype(np.float32))
            first_index += frames
    stats = json.loads((tmp_path / "ds/meta/stats.json").read_text())
    all_states = np.concatenate(states)
    assert stats["observation.state"]["count"] == [len(all_states)]
    np.testing.assert_allclose(stats["observation.state"]["max"], all_states.max(axis=0))
    np.testing.assert_allclose(stats["observation.state"]["mean"], all_states.astype(np.float64).mean(axis=0))
    assert all({"q01", "q99"} <= set(s) for s in stats.values())      # GR00T rejects stats without them
    video = info["features"]["observation.images.stereo_left"]
    assert video["info"]["video.codec"] == "h264" and video["info"]["video.fps"] == fps
    assert np.asarray(stats["observation.images.stereo_left"]["mean"]).shape == (3, 1, 1)


def test_the_same_episodes_give_byte_identical_exports(export_episodes, tmp_path):
    for name in ("a", "b"):
        export_lerobot(export_episodes, tmp_path / name, "v3.0")
    files = sorted(p.relative_to(tmp_path / "a") for p in (tmp_path / "a").rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(tmp_path / "b") for p in (tmp_path / "b").rglob("*") if p.is_file())
    for rel in files:
        assert (tmp_path / "a" / rel).read_bytes() == (tmp_path / "b" / rel).read_bytes(), rel
