"""HDF5 episodes -> one LeRobot dataset folder (v2.1 or v3.0), written beside the target and renamed
into place only when complete.

Each episode is first converted whole into scratch files (its views' MP4s, its frame table, its stats)
and only then placed in the dataset, so an episode that fails part-way (not an episode, a missing view,
a layout that differs from the first episode's) leaves nothing behind; its error is reported and the
other episodes are exported. Camera frames stream through in chunks, so memory stays bounded."""

from __future__ import annotations

import logging
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path

from episodes.atomic import atomic_dir
from episodes.reader import EpisodeReader, open_episode
from lerobot_export import features as F
from lerobot_export.formats import FORMATS, Episode, make_writer
from lerobot_export.modality import modality
from lerobot_export.source import Layout, check_matches, read_layout
from lerobot_export.stats import ImageStats
from lerobot_export.video import VideoSettings, ViewEncoder, video_info
from sim.errors import SpecError

log = logging.getLogger(__name__)


class NothingExported(ValueError):
    """No input episode could be exported; lists why for each."""

    def __init__(self, errors: dict[str, str]):
        self.errors = errors
        lines = "\n".join(f"  {msg if path in msg else f'{path}: {msg}'}" for path, msg in errors.items())
        super().__init__(f"no episode could be exported:\n{lines}" if errors else "no episode files given")


@dataclass
class ExportResult:
    path: Path
    version: str
    episodes: list[Path] = field(default_factory=list)     # in episode-index order
    errors: dict[str, str] = field(default_factory=dict)   # episode file -> what was wrong
    frames: int = 0
    seconds: float = 0.0


def episode_files(inputs: list[Path]) -> list[Path]:
    """Files as given; a folder stands for its *.hdf5 files in name order."""
    out = []
    for p in map(Path, inputs):
        out.extend(sorted(p.glob("*.hdf5")) if p.is_dir() else [p])
    return out


def _encode_views(reader: EpisodeReader, layout: Layout, scratch: Path, settings: VideoSettings):
    videos, stats = {}, {}
    for cam, h, w in layout.views:
        key = F.view_key(cam)
        encoder = ViewEncoder(scratch / f"{key}.mp4", layout.fps, w, h, settings)
        image_stats = ImageStats()
        try:
            for start in range(0, reader.num_frames, F.FRAME_CHUNK):
                frames = reader.read(f"cameras/{cam}/rgb", start, start + F.FRAME_CHUNK)
                encoder.add(frames)
                image_stats.add(frames)
            encoder.close()
        except BaseException:
            encoder.abort()
            raise
        videos[key], stats[key] = encoder.path, image_stats.result()
    return videos, stats


def _prepare(reader: EpisodeReader, layout: Layout, index: int, task_index: int, first_frame: int,
             scratch: Path, settings: VideoSettings) -> Episode:
    task = reader.meta("instruction")
    if not isinstance(task, str) or not task.strip():
        raise SpecError(reader.path, "meta/instruction", "the task instruction (non-empty text)", task)
    table, stats = F.frame_table(reader, layout, F.data_schema(F.info_features(layout, {})), index, task_index,
                                 first_frame)
    videos, video_stats = _encode_views(reader, layout, scratch, settings)
    return Episode(index=index, task=task, table=table, videos=videos, stats={**stats, **video_stats})


def export_lerobot(inputs: list[Path], out: Path, version: str = "v2.1", views: tuple[str, ...] | None = None,
                   tactile: bool = True, video: VideoSettings = VideoSettings(), overwrite: bool = False,
                   **file_limits) -> ExportResult:
    """Export `inputs` (episode files or folders of them) to the LeRobot dataset folder `out`."""
    if version not in FORMATS:
        raise ValueError(f"unknown LeRobot format '{version}'; valid formats: {', '.join(FORMATS)}")
    out = Path(out)
    if out.exists() and not overwrite and not (out.is_dir() and not any(out.iterdir())):
        raise FileExistsError(f"{out}: exists and is not empty; pass overwrite (--overwrite) to replace it")
    started = time.perf_counter()
    result = ExportResult(path=out, version=version)
    layout, writer, video_infos = None, None, {}
    with atomic_dir(out, lambda p: overwrite or (p.is_dir() and not any(p.iterdir()))) as tmp:
        for path in episode_files(inputs):
            scratch = tmp / ".scratch" / str(len(result.episodes))
            scratch.mkdir(parents=True, exist_ok=True)
            try:
                with open_episode(path) as reader:
                    if layout is None:
                        candidate = read_layout(reader, views, tactile)
                    else:
                        check_matches(layout, reader)
                        candidate = layout
                    task_index = writer.task_index(reader.meta("instruction")) if writer else 0
                    episode = _prepare(reader, candidate, len(result.episodes), task_index, result.frames,
                                       scratch, video)
            except Exception as exc:      # one bad episode never stops the others
                log.info("skipped %s", exc if str(path) in str(exc) else f"{path}: {exc}")
                result.errors[str(path)] = str(exc)
                shutil.rmtree(scratch, ignore_errors=True)
                continue
            if writer is None:
                layout = candidate
                writer = make_writer(version, tmp, episode.table.schema, layout.fps, **file_limits)
                video_infos = {key: video_info(mp4, video) for key, mp4 in episode.videos.items()}
            writer.add(episode)
            shutil.rmtree(scratch, ignore_errors=True)
            result.episodes.append(Path(path))
            result.frames += episode.length
            log.info("%s -> episode %d (%d frames)", path, episode.index, episode.length)
        shutil.rmtree(tmp / ".scratch", ignore_errors=True)
        if writer is None:
            raise NothingExported(result.errors)
        feats = F.info_features(layout, video_infos)
        writer.finish(writer.info(layout.fps, layout.robot_type, feats, bool(layout.views)), modality(layout))
    result.seconds = time.perf_counter() - started
    return result
