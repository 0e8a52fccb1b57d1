"""Recorded operator streams: an NPZ file (no pickles) holding a sequence of operator frames.

Layout (version 1), T frames:

    format           str   "b2d-operator-stream"
    version          int   1
    keypoint_frame   str   "wrist" (see frame.py)
    timestamp_ns     (T,)          int64
    keypoints        (T, 2, 21, 3) float64   (side 0 = left, 1 = right)
    wrist_pos        (T, 2, 3)     float64
    wrist_quat       (T, 2, 4)     float64   w x y z
    keypoints_valid  (T, 2)        bool
    wrist_valid      (T, 2)        bool

Frames are stored exactly as they arrived, bad ones included (NaNs, out-of-order timestamps), so a
session replays with the same sanitizer decisions. Files are written to a temporary name and
renamed; they are read with ``allow_pickle=False``.
"""

from __future__ import annotations

import os
import zipfile
from pathlib import Path

import numpy as np

from episodes.atomic import atomic_path

from .frame import NUM_KEYPOINTS, OperatorFrame

FORMAT = "b2d-operator-stream"
VERSION = 1
FIELDS = {   # name -> (shape after T, dtype kind)
    "timestamp_ns": ((), "i"), "keypoints": ((2, NUM_KEYPOINTS, 3), "f"), "wrist_pos": ((2, 3), "f"),
    "wrist_quat": ((2, 4), "f"), "keypoints_valid": ((2,), "b"), "wrist_valid": ((2,), "b"),
}


class StreamFileError(ValueError):
    """A recorded stream file is missing a field or holds one of the wrong shape."""


def write_stream(path: str | os.PathLike, frames: list[OperatorFrame]) -> Path:
    arrays = {
        "format": np.array(FORMAT), "version": np.array(VERSION), "keypoint_frame": np.array("wrist"),
        "timestamp_ns": np.array([f.timestamp_ns for f in frames], np.int64).reshape(len(frames)),
        "keypoints": np.array([f.keypoints for f in frames], np.float64).reshape(len(frames), 2, NUM_KEYPOINTS, 3),
        "wrist_pos": np.array([f.wrist_pos for f in frames], np.float64).reshape(len(frames), 2, 3),
        "wrist_quat": np.array([f.wrist_quat for f in frames], np.float64).reshape(len(frames), 2, 4),
        "keypoints_valid": np.array([f.keypoints_valid for f in frames], bool).reshape(len(frames), 2),
        "wrist_valid": np.array([f.wrist_valid for f in frames], bool).reshape(len(frames), 2),
    }
    # np.savez's layout, written by hand with a fixed entry date so equal frames give equal bytes
    with atomic_path(path) as tmp, zipfile.ZipFile(tmp, "w", zipfile.ZIP_STORED) as zf:
        for name, array in arrays.items():
            info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            with zf.open(info, "w", force_zip64=True) as fh:
                np.lib.format.write_array(fh, np.asanyarray(array), allow_pickle=False)
    return Path(path)


def read_stream(path: str | os.PathLike) -> list[OperatorFrame]:
    path = Path(path)

    def fail(field, msg):
        raise StreamFileError(f"{path}: field '{field}': {msg}")

    try:
        npz = np.load(path, allow_pickle=False)
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:   # EOFError: an empty file
        raise StreamFileError(f"{path}: not a readable NPZ operator stream ({exc})") from None
    if not isinstance(npz, np.lib.npyio.NpzFile):                       # a lone .npy array
        raise StreamFileError(f"{path}: not a readable NPZ operator stream (a single array, not an archive)")

    def get(key):
        try:
            return npz[key]
        except ValueError as exc:      # e.g. an object array, which would need unpickling
            fail(key, f"unreadable without pickle or malformed ({exc})")
        except Exception as exc:     # a damaged entry: zip, zlib, or a .npy header numpy cannot parse (SyntaxError)
            fail(key, f"unreadable entry ({type(exc).__name__}: {str(exc)[:120]})")

    with npz:
        for key, expected in (("format", FORMAT), ("version", VERSION), ("keypoint_frame", "wrist")):
            if key not in npz.files:
                fail(key, f"missing (expected {expected!r})")
            value = get(key)
            if value.shape != () or value.item() != expected:
                fail(key, f"expected {expected!r}, got {value!r}")
        arrays = {}
        for name, (shape, kind) in FIELDS.items():
            if name not in npz.files:
                fail(name, f"missing (expected an array of shape (T, {', '.join(map(str, shape))}))")
            a = get(name)
            if a.dtype.kind != kind or a.ndim != 1 + len(shape) or a.shape[1:] != shape:
                fail(name, f"expected dtype kind {kind!r} and shape (T, {', '.join(map(str, shape))}), "
                           f"got {a.dtype} {a.shape}")
            arrays[name] = a
    lengths = {name: len(a) for name, a in arrays.items()}
    if len(set(lengths.values())) != 1:
        fail("timestamp_ns", f"all fields must have the same number of frames, got {lengths}")
    return [OperatorFrame(int(arrays["timestamp_ns"][i]), arrays["keypoints"][i], arrays["wrist_pos"][i],
                          arrays["wrist_quat"][i], arrays["keypoints_valid"][i], arrays["wrist_valid"][i])
            for i in range(lengths["timestamp_ns"])]


class RecordedStream:
    """Plays a recorded stream back: ``poll()`` returns the next frame in file (arrival) order, one
    per control step; with ``now_ns`` it skips ahead to the last frame stamped at or before
    ``now_ns`` that has not been returned yet (None when there is none: a dropped step, as from a
    live device)."""

    def __init__(self, path: str | os.PathLike):
        self.path = Path(path)
        self.frames = read_stream(self.path)
        self.cursor = 0

    def __len__(self) -> int:
        return len(self.frames)

    def done(self) -> bool:
        return self.cursor >= len(self.frames)

    def poll(self, now_ns: int | None = None) -> OperatorFrame | None:
        if self.done():
            return None
        if now_ns is None:
            self.cursor += 1
            return self.frames[self.cursor - 1]
        newest = None
        while not self.done() and self.frames[self.cursor].timestamp_ns <= now_ns:
            newest = self.frames[self.cursor]
            self.cursor += 1
        return newest
