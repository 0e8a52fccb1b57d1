"""Join HDF5 files that hold consecutive frame ranges of one episode into one file.

Per-frame datasets (extendable along axis 0, as `EpisodeWriter` makes them) are concatenated; the
rest (intrinsics, surface maps, names) is the same in every part and copied once. Image chunks hold
one frame, so they are copied as compressed bytes (`read_direct_chunk`), never decoded and
recompressed: joining costs little next to rendering. Frames the writer left unallocated (all zero)
stay so. The joined datasets keep each part's chunking
and filter pipeline (plugin filters included).
"""

from __future__ import annotations

from pathlib import Path

import h5py
import hdf5plugin  # noqa: F401  (registers the image filters of episodes.writer)
import numpy as np

from episodes.atomic import atomic_path, guarded_h5
from episodes.integrity import datasets as _datasets


def concat_frames(parts: list[Path], out_path: Path, frame_axis_datasets: tuple[str, ...] = ()) -> None:
    """Write `out_path` (atomically) as the frame-wise concatenation of `parts`, in order.

    `frame_axis_datasets` names fixed-size datasets that nevertheless run along the frame axis
    (e.g. the frame step index) and must be concatenated too."""
    if not parts:
        raise ValueError(f"{out_path}: no parts to join")
    files: list[h5py.File] = []
    try:
        for p in parts:     # opened inside the try: a part that fails to open closes the others
            files.append(h5py.File(p, "r"))
        first = _datasets(files[0])
        per_part = [_datasets(f) for f in files]
        for path, sets in zip(parts, per_part):
            if sets.keys() != first.keys():
                missing = sorted(first.keys() ^ sets.keys())
                raise ValueError(f"{path}: datasets differ from {parts[0].name}: {missing[:5]}")
            # chunks are copied as raw bytes: a different dtype or frame shape would be misread
            odd = [n for n, ds in sets.items() if ds.dtype != first[n].dtype or ds.shape[1:] != first[n].shape[1:]]
            if odd:
                raise ValueError(f"{path}: dtype or frame shape differs from {parts[0].name} in {odd[:5]}")
        with atomic_path(out_path) as tmp, guarded_h5(tmp) as out:
            out.attrs.update(dict(files[0].attrs))
            for name, ds in first.items():
                if (ds.ndim and ds.maxshape[0] is None) or name in frame_axis_datasets:
                    _concat(out, name, [sets[name] for sets in per_part])
                else:
                    files[0].copy(ds, out, name=name)
    finally:
        for f in files:
            f.close()


def copy_in_name_order(src: h5py.Group, dst: h5py.File, name: str) -> None:
    """Copy group `src` to `dst[name]` dataset by dataset, in name order, its groups made afresh.

    Copying the group whole (H5Ocopy) keeps the source's object headers as its writing history left
    them: a render written frame by frame and one joined from parts hold the same datasets, but the
    episodes copied from them differed in bytes (groups of more than 8 links differ in layout). Copied
    this way the episode's bytes depend only on the content (issue 23: the same sha256 for any number
    of render workers)."""
    groups = {"": src}
    src.visititems(lambda path, obj: groups.__setitem__(path, obj) if isinstance(obj, h5py.Group) else None)
    for path, group in sorted(groups.items()):      # groups' attributes, if any, come along
        made = dst.require_group(f"{name}/{path}" if path else name)
        for key in sorted(group.attrs):
            made.attrs[key] = group.attrs[key]
    for path, ds in sorted(_datasets(src).items()):
        parent, _, leaf = f"{name}/{path}".rpartition("/")
        src.file.copy(ds, dst[parent], name=leaf)


def _filters(ds: h5py.Dataset) -> tuple:
    """The dataset's filter pipeline (id, flags, parameters per filter), plugin filters included."""
    dcpl = ds.id.get_create_plist()
    return tuple(dcpl.get_filter(i)[:3] for i in range(dcpl.get_nfilters()))


def _create_like(out: h5py.File, name: str, src: h5py.Dataset, total: int) -> h5py.Dataset:
    """An extendable dataset of `total` frames with the source's chunks and filters (its creation
    property list): plugin filters (hdf5plugin's Zstd, Blosc) carry over, which h5py's
    `compression=` keyword cannot name."""
    if src.chunks is None:      # a small contiguous dataset along the frame axis, kept contiguous as one writer makes it
        return out.create_dataset(name, shape=(total, *src.shape[1:]), dtype=src.dtype)
    space = h5py.h5s.create_simple((total, *src.shape[1:]), (h5py.h5s.UNLIMITED, *src.shape[1:]))
    # no timestamps: a source's creation property list reads back with HDF5's default (record the
    # creation time), and the joined file's bytes then changed from run to run (issue 23). Parent groups
    # through h5py, which makes them without timestamps too.
    dcpl = src.id.get_create_plist()
    dcpl.set_obj_track_times(False)
    parent, _, leaf = name.rpartition("/")
    group = out.require_group(parent) if parent else out
    dsid = h5py.h5d.create(group.id, leaf.encode(), src.id.get_type(), space, dcpl=dcpl)
    return h5py.Dataset(dsid)


def _concat(out: h5py.File, name: str, sources: list[h5py.Dataset]) -> None:
    src = sources[0]
    total = sum(s.shape[0] for s in sources)
    dst = _create_like(out, name, src, total)
    one_frame_chunks = src.chunks is not None and src.chunks[0] == 1
    start = 0
    for s in sources:
        n = s.shape[0]
        same_fill = np.asarray(s.fillvalue).tobytes() == np.asarray(src.fillvalue).tobytes()
        if one_frame_chunks and s.chunks == src.chunks and _filters(s) == _filters(src) and same_fill:
            # the allocated chunks only: a frame the writer did not store (all zero) reads as the fill value
            tail = (0,) * (len(s.shape) - 1)
            for i in range(n):
                if s.id.get_chunk_info_by_coord((i, *tail)).byte_offset is None:
                    continue
                mask, chunk = s.id.read_direct_chunk((i, *tail))
                dst.id.write_direct_chunk((start + i, *tail), chunk, mask)
        else:
            dst[start:start + n] = s[()] if n else np.empty((0, *s.shape[1:]), s.dtype)
        start += n
