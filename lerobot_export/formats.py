"""Where each piece of a LeRobot dataset goes, in the two on-disk versions lerobot reads.

v2.1 (what GR00T N1.5 and openpi train on): one parquet and one MP4 per view per episode, metadata as
JSON lines (meta/episodes.jsonl, tasks.jsonl, episodes_stats.jsonl). v3.0 (lerobot's current format):
several episodes per parquet and per MP4 (an episode's video is found by its from/to timestamps), a
new file once one passes a size limit, metadata as parquet (meta/tasks.parquet, meta/episodes/...)
with each episode's stats as `stats/<feature>/<stat>` columns. Both get meta/info.json, meta/stats.json
and GR00T's meta/modality.json."""

from __future__ import annotations

import json
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from lerobot_export.stats import aggregate, to_json
from lerobot_export.video import JoinedVideo

FORMATS = ("v2.1", "v3.0")
CHUNK_SIZE = 1000                      # lerobot's files per chunk folder
DATA_FILE_MB, VIDEO_FILE_MB = 100, 200  # lerobot v3.0's default file size limits
V21_DATA = "data/chunk-{episode_chunk:03d}/episode_{episode_index:06d}.parquet"
V21_VIDEO = "videos/chunk-{episode_chunk:03d}/{video_key}/episode_{episode_index:06d}.mp4"
V30_DATA = "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
V30_VIDEO = "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
V30_EPISODES = "meta/episodes/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"


def write_json(path: Path, data) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=4, ensure_ascii=False) + "\n", encoding="utf-8")


def write_jsonl(path: Path, rows: list[dict]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(json.dumps(r, ensure_ascii=False) + "\n" for r in rows), encoding="utf-8")


@dataclass
class Episode:
    """One exported episode, ready to be placed: its frame table, its views' MP4s (scratch files) and
    the stats of every feature."""
    index: int
    task: str
    table: pa.Table
    videos: dict[str, Path]
    stats: dict
    length: int = field(init=False)

    def __post_init__(self):
        self.length = self.table.num_rows


class _Writer:
    version: str

    def __init__(self, root: Path, schema: pa.Schema):
        self.root, self.schema = root, schema
        self.episodes: list[dict] = []
        self.episode_stats: list[dict] = []
        self.tasks: list[str] = []
        self.frames = 0

    def task_index(self, task: str) -> int:
        """The index `task` has, or will have once an episode with it is added."""
        return self.tasks.index(task) if task in self.tasks else len(self.tasks)

    def add(self, episode: Episode) -> None:
        if episode.task not in self.tasks:
            self.tasks.append(episode.task)
        self.episode_stats.append(episode.stats)
        self.frames += episode.length

    def info(self, fps: int, robot_type: str, features: dict, has_videos: bool) -> dict:
        return {"codebase_version": self.version, "robot_type": robot_type,
                "total_episodes": len(self.episodes), "total_frames": self.frames, "total_tasks": len(self.tasks)}

    def finish(self, info: dict, modality: dict) -> None:
        write_json(self.root / "meta/info.json", info)
        if self.episode_stats:
            write_json(self.root / "meta/stats.json", to_json(aggregate(self.episode_stats)))
        write_json(self.root / "meta/modality.json", modality)


class V21Writer(_Writer):
    version = "v2.1"

    def add(self, episode: Episode) -> None:
        chunk = episode.index // CHUNK_SIZE
        path = self.root / V21_DATA.format(episode_chunk=chunk, episode_index=episode.index)
        path.parent.mkdir(parents=True, exist_ok=True)
        pq.write_table(episode.table, path)
        for key, mp4 in episode.videos.items():
            final = self.root / V21_VIDEO.format(episode_chunk=chunk, video_key=key, episode_index=episode.index)
            final.parent.mkdir(parents=True, exist_ok=True)
            shutil.move(mp4, final)
        self.episodes.append({"episode_index": episode.index, "tasks": [episode.task], "length": episode.length})
        super().add(episode)

    def info(self, fps, robot_type, features, has_videos) -> dict:
        n = len(self.episodes)
        views = sum(1 for f in features.values() if f["dtype"] == "video")
        return {**super().info(fps, robot_type, features, has_videos), "total_videos": n * views,
                "total_chunks": -(-n // CHUNK_SIZE), "chunks_size": CHUNK_SIZE, "fps": fps,
                "splits": {"train": f"0:{n}"}, "data_path": V21_DATA,
                "video_path": V21_VIDEO if has_videos else None, "features": features}

    def finish(self, info: dict, modality: dict) -> None:
        meta = self.root / "meta"
        write_jsonl(meta / "episodes.jsonl", self.episodes)
        write_jsonl(meta / "tasks.jsonl", [{"task_index": i, "task": t} for i, t in enumerate(self.tasks)])
        write_jsonl(meta / "episodes_stats.jsonl", [{"episode_index": e["episode_index"], "stats": to_json(s)}
                                                    for e, s in zip(self.episodes, self.episode_stats)])
        super().finish(info, modality)


def _next_file(chunk: int, file: int) -> tuple[int, int]:
    return (chunk + 1, 0) if file == CHUNK_SIZE - 1 else (chunk, file + 1)


class V30Writer(_Writer):
    version = "v3.0"

    def __init__(self, root: Path, schema: pa.Schema, fps: int, data_mb: float = DATA_FILE_MB,
                 video_mb: float = VIDEO_FILE_MB):
        super().__init__(root, schema)
        self.fps, self.data_mb, self.video_mb = fps, data_mb, video_mb
        self._data = None                 # (chunk, file, ParquetWriter, bytes written)
        self._videos: dict[str, tuple[int, int, JoinedVideo]] = {}

    def _data_file(self, incoming: int) -> tuple[int, int, pq.ParquetWriter]:
        if self._data is not None and self._data[3] and self._data[3] + incoming > self.data_mb * 2 ** 20:
            self._data[2].close()
            chunk, file = _next_file(self._data[0], self._data[1])
            self._data = None
        elif self._data is None:
            chunk, file = 0, 0
        if self._data is None:
            path = self.root / V30_DATA.format(chunk_index=chunk, file_index=file)
            path.parent.mkdir(parents=True, exist_ok=True)
            self._data = [chunk, file, pq.ParquetWriter(path, self.schema), 0]
        return self._data[0], self._data[1], self._data[2]

    def _video_file(self, key: str, incoming: int) -> tuple[int, int, JoinedVideo]:
        current = self._videos.get(key)
        if current is not None and current[2].bytes_in and current[2].bytes_in + incoming > self.video_mb * 2 ** 20:
            current[2].close()
            chunk, file = _next_file(current[0], current[1])
            current = None
        elif current is None:
            chunk, file = 0, 0
        if current is None:
            joined = JoinedVideo(self.root / V30_VIDEO.format(video_key=key, chunk_index=chunk, file_index=file),
                                 self.fps)
            current = self._videos[key] = (chunk, file, joined)
        return current

    def add(self, episode: Episode) -> None:
        chunk, file, writer = self._data_file(episode.table.nbytes)
        writer.write_table(episode.table)       # one row group per episode, as lerobot writes them
        self._data[3] += episode.table.nbytes
        row = {"episode_index": episode.index, "tasks": [episode.task], "length": episode.length,
               "data/chunk_index": chunk, "data/file_index": file,
               "dataset_from_index": self.frames, "dataset_to_index": self.frames + episode.length}
        for key, mp4 in episode.videos.items():
            v_chunk, v_file, joined = self._video_file(key, mp4.stat().st_size)
            start, end = joined.append(mp4)
            mp4.unlink()
            row.update({f"videos/{key}/chunk_index": v_chunk, f"videos/{key}/file_index": v_file,
                        f"videos/{key}/from_timestamp": start, f"videos/{key}/to_timestamp": end})
        row.update({f"stats/{feature}/{name}": value.tolist()
                    for feature, s in episode.stats.items() for name, value in s.items()})
        row.update({"meta/episodes/chunk_index": 0, "meta/episodes/file_index": 0})
        self.episodes.append(row)
        super().add(episode)

    def close_files(self) -> None:
        if self._data is not None:
            self._data[2].close()
            self._data = None
        for _, _, joined in self._videos.values():
            joined.close()
        self._videos = {}

    def info(self, fps, robot_type, features, has_videos) -> dict:
        n = len(self.episodes)
        return {**super().info(fps, robot_type, features, has_videos), "chunks_size": CHUNK_SIZE,
                "data_files_size_in_mb": self.data_mb, "video_files_size_in_mb": self.video_mb, "fps": fps,
                "splits": {"train": f"0:{n}"}, "data_path": V30_DATA,
                "video_path": V30_VIDEO if has_videos else None, "features": features}

    def finish(self, info: dict, modality: dict) -> None:
        self.close_files()
        tasks = pd.DataFrame({"task_index": range(len(self.tasks))}, index=pd.Index(self.tasks, name="task"))
        (self.root / "meta").mkdir(parents=True, exist_ok=True)
        tasks.to_parquet(self.root / "meta/tasks.parquet")
        if self.episodes:
            path = self.root / V30_EPISODES.format(chunk_index=0, file_index=0)
            path.parent.mkdir(parents=True, exist_ok=True)
            pq.write_table(pa.Table.from_pylist(self.episodes), path)
        super().finish(info, modality)


def make_writer(version: str, root: Path, schema: pa.Schema, fps: int, **limits) -> _Writer:
    if version == "v2.1":
        return V21Writer(root, schema)
    if version == "v3.0":
        return V30Writer(root, schema, fps, **limits)
    raise ValueError(f"unknown LeRobot format '{version}'; valid formats: {', '.join(FORMATS)}")
