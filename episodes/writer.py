"""Stream an episode into the paper's HDF5 layout, one frame at a time, in bounded memory.

The file is written under a temporary name and renamed when complete, so a failing episode
leaves nothing behind. Frames that cannot be fully captured are kept and flagged in
`frame_valid` / `frame_errors` instead of aborting the episode.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import h5py
import hdf5plugin  # registers the image filters (image_filter)
import numpy as np

from episodes import schema
from episodes.atomic import WriteGuard, atomic_path

# Blosc splits a chunk among threads and the compressed bytes then depend on the thread count
# (BLOSC_NTHREADS=4 gave three different files in three runs); one thread keeps files byte-identical.
# The filter reads the variable when it runs, so setting it here covers every file b2d writes.
os.environ["BLOSC_NTHREADS"] = "1"

STR = h5py.string_dtype()
SMALL_FRAME_BYTES = 4096     # per-frame values below this are buffered (bounded: a few KB per frame)
# buffered values are written this many frames at a time: HDF5's calls per dataset (~0.1 ms) are paid once
# a block, and mostly while frames are still being rendered, not at the file's close, which is the one
# part of a render its helper processes cannot share
SMALL_BLOCK_FRAMES = 32


def image_filter(dtype: np.dtype) -> dict:
    """HDF5 filter of a per-frame image dataset: Zstandard level 1 for integer and bool images (RGB,
    masks, occupancy, tactile maps), Blosc LZ4 with byte shuffle for float images (metric depth, tactile
    distance). On paper frames (six 640x480 RGB-D cameras with labels and tactile) they write ~2.5x faster
    than LZF and store less (figures: README "Episode files"). Both are HDF5 plugin filters shipped by
    `hdf5plugin`, which must be imported before such a file is read or written."""
    if np.dtype(dtype).kind == "f":
        return dict(hdf5plugin.Blosc(cname="lz4", clevel=5, shuffle=hdf5plugin.Blosc.SHUFFLE))
    return dict(hdf5plugin.Zstd(clevel=1))


class EpisodeWriter:
    """Usage: `with EpisodeWriter(path, static) as w: w.append(frame) ...`.

    `static` holds what does not change per frame (meta, names, intrinsics); each `frame` is a
    dict of relative dataset paths -> per-frame arrays (e.g. "cameras/chest/rgb": HxWx3)."""

    def __init__(self, path: str | Path, static: dict):
        self.path = Path(path)
        self.static = static
        self._atomic = atomic_path(self.path)
        self._file: h5py.File | None = None
        self._count = 0
        # open handles, kept for the whole episode: dropping one flushes its chunk cache, which
        # recompresses a partly filled 256-frame chunk on every append (~4 ms per small dataset;
        # one-frame image chunks have no cache: see _no_chunk_cache)
        self._datasets: dict[str, _Stream] = {}
        # small per-frame values (boxes, poses, flags, error text) are kept in memory and written
        # SMALL_BLOCK_FRAMES frames at a time (error text at the end): appending to ~150 tiny datasets
        # cost ~0.1 ms each per frame in HDF5 calls
        self._small: dict[str, list[tuple[int, object]]] = {}      # rows not written yet
        self._small_datasets: dict[str, h5py.Dataset] = {}
        # per key, from its first frame: its row shape (None: text) and whether it is buffered
        self._layout: dict[str, tuple[tuple | None, bool]] = {}

    def __enter__(self) -> "EpisodeWriter":
        tmp = self._atomic.__enter__()
        # through a WriteGuard: a full disk is an OSError on closing, not a crash of HDF5 (issue 23)
        self._guard = WriteGuard(tmp)
        self._file = h5py.File(self._guard, "w")
        self._file.attrs["schema_version"] = schema.SCHEMA_VERSION
        for key, value in self.static.items():
            self._write_static(key, value)
        return self

    def _write_static(self, key: str, value) -> None:
        if isinstance(value, str):
            self._file.create_dataset(key, data=value, dtype=STR)
        elif isinstance(value, (list, tuple)) and value and isinstance(value[0], str):
            self._file.create_dataset(key, data=list(value), dtype=STR)
        elif isinstance(value, dict):
            self._file.create_dataset(key, data=json.dumps(value, sort_keys=True), dtype=STR)
        else:
            value = np.asarray(value)
            # large static arrays (tactile surface maps) compress like per-frame images; scalars cannot
            packed = {**image_filter(value.dtype), "fletcher32": True} if value.size >= 1024 else {}
            self._file.create_dataset(key, data=value, **packed)

    def append(self, frame: dict) -> None:
        values = {key: value if isinstance(value, str) else np.asarray(value) for key, value in frame.items()}
        layout = {key: self._row_layout(key, value) for key, value in values.items()}   # checks all first
        self._layout.update(layout)       # a refused frame leaves no layout behind for its new keys
        buffered = {key: small for key, (_, small) in layout.items()}
        for key, value in values.items():
            if buffered[key]:
                # a copy: callers pass views into MjData that change with the next step
                self._small.setdefault(key, []).append((self._count, value if isinstance(value, str) else value.copy()))
                continue
            stream = self._datasets.get(key)
            if stream is None:
                stream = self._datasets[key] = _Stream(self._create(key, value))
            stream.write(self._count, value)
        self._count += 1
        if self._count % SMALL_BLOCK_FRAMES == 0:
            self._write_small()

    def _row_layout(self, key: str, value) -> tuple[tuple | None, bool]:
        """``key``'s row shape (None: text) and whether its frames are kept in memory until close, both
        from its first frame; a later frame of another shape (text for an array) is refused."""
        shape = None if isinstance(value, str) else value.shape
        first, buffered = self._layout.get(key, (shape, shape is None or value.nbytes < SMALL_FRAME_BYTES))
        if shape != first:
            expected = "text" if first is None else f"shape {first}"
            got = "text" if shape is None else f"shape {shape}"
            raise ValueError(f"{self.path}: frame {self._count} of '{key}': expected {expected} as in its first "
                             f"frame, got {got}")
        return first, buffered

    def _create(self, key: str, value: np.ndarray) -> h5py.Dataset:
        image_like = value.ndim >= 2 and value.size >= 1024
        # the other per-frame values (poses, boxes, flags, actions) take Zstandard level 1 as well: it
        # stores 3% less than gzip 4 + shuffle did and writes in 40% of the time (README "Episode
        # files"); their write is the file's close, which no render helper shares
        kwargs = image_filter(value.dtype) if image_like else dict(hdf5plugin.Zstd(clevel=1))
        # a checksum of each stored chunk: HDF5 refuses to read a chunk whose bytes changed. Zstd and
        # LZ4 decode most flipped bytes without noticing (issue 23); this costs little (compressed bytes)
        kwargs["fletcher32"] = True
        frames = schema.IMAGE_CHUNK_FRAMES if image_like else 256
        if frames == 1:     # each chunk is written whole, once, and never read back: a cache only adds a copy
            kwargs["dapl"] = _no_chunk_cache()
        return self._file.create_dataset(key, shape=(0, *value.shape), maxshape=(None, *value.shape),
                                         dtype=value.dtype, chunks=(frames, *value.shape), **kwargs)

    def _write_small(self, final: bool = False) -> None:
        """Write the buffered small per-frame values, one dataset each, as if appended frame by frame
        (a key first seen at frame k gets zero / empty rows before k). Text is written only when
        `final`, whole."""
        for key, rows in self._small.items():
            if not rows:
                continue
            if isinstance(rows[0][1], str):
                if final:
                    text = [""] * (rows[-1][0] + 1)
                    for i, value in rows:
                        text[i] = value
                    self._file.create_dataset(key, data=text, dtype=STR, maxshape=(None,), chunks=(256,))
                continue
            ds = self._small_datasets.get(key)
            if ds is None:      # of the key's first value's dtype: later values are cast as numpy casts
                ds = self._small_datasets[key] = self._create(key, np.asarray(rows[0][1]))
            start, stop = rows[0][0], rows[-1][0] + 1
            if stop - start == len(rows):     # a value in every frame (the usual case): one stack
                block = np.stack([value for _, value in rows]).astype(ds.dtype, copy=False)
            else:       # frames without the key keep zeros (rows after this block's are not written yet)
                block = np.zeros((stop - start, *ds.shape[1:]), ds.dtype)
                for i, value in rows:
                    block[i - start] = value
            _write_rows(ds, start, block)
            rows.clear()
        if final:
            self._small.clear()

    @property
    def file(self) -> h5py.File:
        return self._file

    def write_final(self, key: str, value) -> None:
        """Datasets known only at the end (episode metrics, success flags)."""
        self._datasets.pop(key, None)
        self._small.pop(key, None)
        self._small_datasets.pop(key, None)
        self._layout.pop(key, None)
        if key in self._file:
            del self._file[key]
        self._write_static(key, value)

    @property
    def frames_written(self) -> int:
        return self._count

    def __exit__(self, exc_type, exc, tb) -> None:
        try:
            try:
                if exc_type is None:
                    for stream in self._datasets.values():
                        stream.trim()
                    self._write_small(final=True)
            finally:
                self._datasets.clear()
                self._small_datasets.clear()
                try:
                    self._file.close()
                finally:
                    self._guard.close()     # raises a write error it kept (disk full)
        except BaseException as err:        # finishing failed: the temporary file goes, nothing is renamed
            self._atomic.__exit__(type(err), err, err.__traceback__)
            raise
        self._atomic.__exit__(exc_type, exc, tb)


class _Stream:
    """A per-frame dataset written one frame at a time: grown `GROW` frames at a time and trimmed on
    closing, each frame written to its row by a hyperslab selection. h5py's `resize` + `ds[i] = value`
    cost ~0.2 ms per dataset and frame, a third of a paper frame's write over its ~56 image datasets.

    A frame whose bytes are all zero is not written: its one-frame chunk stays unallocated and reads
    back as the fill value, 0 (a tactile site out of contact, an empty mask). Such frames cost no
    compression and no space; the arrays read back are the same."""

    GROW = 64

    def __init__(self, ds: h5py.Dataset):
        self.ds = ds
        self.frame_shape = ds.shape[1:]
        self.capacity = ds.shape[0]
        self.length = 0            # last written frame + 1: the dataset's length when closed
        self._memory = h5py.h5s.create_simple((1, *self.frame_shape))
        self._start = (0,) * len(self.frame_shape)
        # only where a row is its own chunk and the fill value is zero bytes
        self.skip_zeros = ds.chunks is not None and ds.chunks[0] == 1 and _all_zero_bytes(np.asarray(ds.fillvalue))

    def write(self, index: int, value: np.ndarray) -> None:
        if index >= self.capacity:
            self.capacity = index + self.GROW
            self.ds.resize(self.capacity, axis=0)
        if value.shape != self.frame_shape:     # broadcast (or fail) as h5py does
            self.ds[index] = value
        elif self.skip_zeros and _all_zero_bytes(value):
            pass                                # an unallocated chunk reads as the fill value
        else:   # HDF5 converts the dtype if it differs, as h5py's ds[index] = value does
            row = self.ds.id.get_space()
            row.select_hyperslab((index, *self._start), (1, *self.frame_shape))
            self.ds.id.write(self._memory, row, np.ascontiguousarray(value).reshape(1, *self.frame_shape))
        self.length = index + 1

    def trim(self) -> None:
        if self.capacity != self.length:
            self.ds.resize(self.length, axis=0)
            self.capacity = self.length


def _write_rows(ds: h5py.Dataset, start: int, rows: np.ndarray) -> None:
    """``ds[start:start + len(rows)] = rows``, growing ``ds`` to end there, through HDF5's own calls:
    through h5py's resize and slicing a preview render's small values took 85 ms, through these 50."""
    ds.id.set_extent((start + len(rows), *rows.shape[1:]))
    space = ds.id.get_space()
    space.select_hyperslab((start,) + (0,) * (rows.ndim - 1), rows.shape)
    ds.id.write(h5py.h5s.create_simple(rows.shape), space, np.ascontiguousarray(rows))


def _no_chunk_cache() -> h5py.h5p.PropDAID:
    """Dataset access without a chunk cache (paper frames: image writes ~22 -> ~18 ms a frame, the same
    chunks). h5py's create_dataset ignores ``rdcc_nbytes=0`` (it only applies a truthy value)."""
    dapl = h5py.h5p.create(h5py.h5p.DATASET_ACCESS)
    slots, _, preemption = dapl.get_chunk_cache()
    dapl.set_chunk_cache(slots, 0, preemption)
    return dapl


def _all_zero_bytes(value: np.ndarray) -> bool:
    """Whether every byte of ``value`` is zero (-0.0 is not: its chunk must keep the sign bit). The
    first and last bytes are looked at first: camera images and depth rarely start with zeros, so
    most checks stop there."""
    raw = np.ascontiguousarray(value).reshape(-1).view(np.uint8)
    if not raw.size or raw[0] or raw[-1]:
        return not raw.size
    # eight bytes at a time; an unsigned max is a plain SIMD reduction, ~4x numpy's any() here
    words = raw[: raw.size - raw.size % 8].view(np.uint64)
    return not ((words.size and words.max()) or raw[words.size * 8:].any())
