"""One camera view of one episode as an MP4 (PyAV), and episode MP4s joined into one file by remuxing.

Settings are fixed so two exports of the same episode are byte-identical: libx264 on one thread (its
multi-threaded slicing depends on timing), no B-frames (decode order = display order, so joining files
only shifts timestamps), a keyframe every `gop` frames for random access, constant quality (CRF).
The codec facts lerobot records under a video feature's `info` come from the written stream itself."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import av
import numpy as np


# swscale picks its thread count from the CPUs by default and its SIMD paths round; one thread with
# bit-exact, accurately rounded arithmetic gives the same YUV planes in every process.
_EXACT_SCALING = (av.video.reformatter.Interpolation.BILINEAR | av.video.reformatter.Interpolation.BITEXACT
                  | av.video.reformatter.Interpolation.ACCURATE_RND)


@dataclass(frozen=True)
class VideoSettings:
    codec: str = "libx264"
    pix_fmt: str = "yuv420p"
    crf: int = 18
    gop: int = 2          # lerobot's default `g`: a keyframe every 2 frames keeps seeking cheap
    preset: str = "medium"

    def options(self) -> dict[str, str]:
        options = {"crf": str(self.crf), "g": str(self.gop), "preset": self.preset, "bf": "0", "threads": "1"}
        if self.codec == "libx264" and _has_avx512():
            options["x264-params"] = "asm=AVX2"
        return options


@functools.cache
def _has_avx512() -> bool:
    """libx264's AVX-512 kernels (x264 core 165) gave different bytes for the same frames in 4 of 30 fresh
    processes, and more often after rendering in the same process; its AVX2 kernels gave the same bytes in
    30 of 30 and otherwise the same files. A CPU with AVX-512 also has AVX2, so masking it down is safe."""
    try:
        with open("/proc/cpuinfo") as cpuinfo:
            return any(line.startswith("flags") and " avx512f" in line for line in cpuinfo)
    except OSError:
        return False


class ViewEncoder:
    """Frames in (uint8 [H, W, 3] RGB), an MP4 out; frame i is shown at i / fps seconds."""

    def __init__(self, path: Path, fps: int, width: int, height: int, settings: VideoSettings):
        self.path, self.fps, self.settings = Path(path), fps, settings
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._container = av.open(str(self.path), "w", format="mp4")
        self._stream = self._container.add_stream(settings.codec, rate=fps, options=settings.options())
        self._stream.width, self._stream.height, self._stream.pix_fmt = width, height, settings.pix_fmt
        self._stream.codec_context.thread_count = 1
        self._reformatter = av.video.reformatter.VideoReformatter()
        self.frames = 0

    def add(self, frames: np.ndarray) -> None:
        for image in frames:
            frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(image), format="rgb24")
            frame = self._reformatter.reformat(frame, format=self.settings.pix_fmt, threads=1,
                                               interpolation=_EXACT_SCALING)
            frame.pts = self.frames
            self._container.mux(self._stream.encode(frame))
            self.frames += 1

    def close(self) -> None:
        if self._container is not None:
            self._container.mux(self._stream.encode())
            self._container.close()
            self._container = None

    def abort(self) -> None:
        if self._container is not None:
            self._container.close()
            self._container = None
        self.path.unlink(missing_ok=True)


def video_info(path: Path, settings: VideoSettings) -> dict:
    """The `info` block lerobot stores beside a video feature (stream facts, then encoder settings)."""
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        info = {
            "video.height": stream.height,
            "video.width": stream.width,
            "video.codec": stream.codec_context.codec.canonical_name,
            "video.pix_fmt": stream.pix_fmt,
            "video.is_depth_map": False,
            "video.fps": int(stream.base_rate),
            "video.channels": len(av.VideoFormat(stream.pix_fmt).components),
            "has_audio": bool(container.streams.audio),
        }
    info.update({"video.g": settings.gop, "video.crf": settings.crf, "video.preset": settings.preset})
    return info


class JoinedVideo:
    """Episode MP4s appended one after another into one MP4 without re-encoding (lerobot v3.0 keeps
    several episodes per video file and finds each by its from/to timestamps)."""

    def __init__(self, path: Path, fps: int):
        self.path, self.fps = Path(path), fps
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._container = av.open(str(self.path), "w", format="mp4")
        self._stream = None
        self._ticks = 0           # next episode's first pts, in the stream's time base
        self.frames = 0
        self.bytes_in = 0

    def append(self, episode_mp4: Path) -> tuple[float, float]:
        """Append one episode's file; returns its (from_timestamp, to_timestamp) in seconds."""
        start_frames = self.frames
        with av.open(str(episode_mp4)) as source:
            src = source.streams.video[0]
            if self._stream is None:
                self._stream = self._container.add_stream_from_template(src)
                self._stream.time_base = src.time_base
            per_frame = 1 / (Fraction(src.time_base) * self.fps)
            if per_frame.denominator != 1:
                raise ValueError(f"{episode_mp4}: time base {src.time_base} holds no whole frame at {self.fps} fps")
            for packet in source.demux(src):
                if packet.dts is None:    # the demuxer's empty flush packet
                    continue
                packet.pts += self._ticks
                packet.dts += self._ticks
                packet.stream = self._stream
                self._container.mux(packet)
            frames = src.frames
        self._ticks += frames * int(per_frame)
        self.frames += frames
        self.bytes_in += Path(episode_mp4).stat().st_size
        return start_frames / self.fps, self.frames / self.fps

    def close(self) -> None:
        if self._container is not None:
            self._container.close()
            self._container = None
