"""Is an episode's data intact? A full decode, and digests of each dataset's stored bytes.

A schema check reads names, types and shapes only, so a flipped bit in an image chunk passed it
(issue 23: 0 of 300 random flips reported). Two further checks:

- `decode_problems`: read every dataset, chunk by chunk (bounded memory); a chunk its filter cannot
  decode (Zstd, Blosc, gzip and its checksum) is reported with its dataset and frame.
- `dataset_digests`: a short digest per dataset of the bytes as stored (compressed chunks read raw,
  not decoded, so hashing costs about what reading the file does). `episode_manifest.json` keeps them
  beside the file's sha256; a file whose sha256 no longer matches is compared dataset by dataset, so
  the report names what changed - also where a flip still decodes (an uncompressed dataset, a byte
  of an LZ4 literal), which no decoder can notice.
"""

from __future__ import annotations

import hashlib

import h5py
import hdf5plugin  # noqa: F401  (registers the image filters: the data is decoded)
import numpy as np

# decoded bytes a dataset may claim per stored byte of the whole file: all-zero frames are not stored
# (episodes/writer.py), so a large ratio is legitimate; a corrupt header claims far more
PLAUSIBLE_EXPANSION = 10_000
DIGEST_CHARS = 16    # 64 bits: enough to notice a change, small enough for a manifest of many episodes


def datasets(f: h5py.File) -> dict[str, h5py.Dataset]:
    found: dict[str, h5py.Dataset] = {}

    def keep(name, obj) -> None:      # must return None: visititems stops at the first other value
        if isinstance(obj, h5py.Dataset):
            found[name] = obj

    f.visititems(keep)
    return dict(sorted(found.items()))


def _stored_bytes(ds: h5py.Dataset):
    """The dataset's bytes as stored: raw chunks for chunked numeric data, else the decoded value
    (small static datasets; variable-length strings, whose chunks hold heap addresses)."""
    if ds.chunks is not None and ds.dtype.kind not in "OSU" and h5py.check_string_dtype(ds.dtype) is None:
        for i in range(ds.id.get_num_chunks()):
            info = ds.id.get_chunk_info(i)
            yield repr(info.chunk_offset).encode()
            yield ds.id.read_direct_chunk(info.chunk_offset)[1]
        yield repr(ds.shape).encode()
        return
    value = ds[()]
    yield value.tobytes() if isinstance(value, np.ndarray) and value.dtype.kind not in "OSU" else repr(value).encode()


def dataset_digests(f: h5py.File) -> dict[str, str]:
    """{dataset path: digest of its stored bytes, dtype and shape}."""
    out = {}
    for name, ds in datasets(f).items():
        digest = hashlib.blake2b(f"{ds.dtype.str}{ds.shape}".encode(), digest_size=DIGEST_CHARS // 2)
        for block in _stored_bytes(ds):
            digest.update(block)
        out[name] = digest.hexdigest()
    return out


def decode_problems(f: h5py.File) -> list[str]:
    """Read every dataset whole, one chunk row at a time; one line per dataset that fails."""
    problems = []
    file_bytes = max(1, f.id.get_filesize())
    for name, ds in datasets(f).items():
        try:
            claimed = int(np.prod(ds.shape, dtype=np.float64) * ds.dtype.itemsize)
            if claimed > PLAUSIBLE_EXPANSION * file_bytes:
                # a flipped bit in a header can claim 2^40 frames: decoding that would never end
                problems.append(f"{name}: shape {ds.shape} claims {claimed:.3g} bytes, implausible in a file of "
                                f"{file_bytes} bytes: the header is corrupt")
                continue
            if ds.chunks is None or not ds.shape:
                ds[()]
                continue
            step = ds.chunks[0]
            for start in range(0, ds.shape[0], step):
                try:
                    ds[start:start + step]
                except Exception as exc:
                    problems.append(f"{name}: frames {start}-{min(start + step, ds.shape[0]) - 1} cannot be "
                                    f"decoded ({short_error(exc)}): the data is corrupt")
                    break
        except Exception as exc:
            problems.append(f"{name}: cannot be decoded ({short_error(exc)}): the data is corrupt")
    return problems


def short_error(exc: Exception) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}"[:200]


def compare_digests(listed: dict[str, str], found: dict[str, str], source: str) -> list[str]:
    """Datasets missing, added or changed against the digests `source` (the manifest) recorded."""
    problems = [f"{name}: missing (listed in {source})" for name in sorted(listed.keys() - found.keys())]
    problems += [f"{name}: not in {source} (added after the episode was written)"
                 for name in sorted(found.keys() - listed.keys())]
    problems += [f"{name}: stored bytes differ from {source} (the data changed after it was written)"
                 for name in sorted(listed.keys() & found.keys()) if listed[name] != found[name]]
    return problems
