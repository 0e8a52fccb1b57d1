"""Write-then-rename, so a crash or a bad episode never leaves a half-written file behind."""

from __future__ import annotations

import contextlib
import hashlib
import io
import logging
import os
import re
import shutil
import tempfile
from pathlib import Path

from episodes.processes import is_running

log = logging.getLogger(__name__)


def temporary_beside(final: Path, tag: str = "tmp", keep_suffix: bool = False) -> Path:
    """A hidden, per-process name beside `final`. `keep_suffix` ends it in `final`'s suffix, for
    writers that choose the format from it (OpenCV video, USD); by default it ends in `.tmp-<pid>`,
    so globs for finished files (`*.hdf5`) never match a file being written."""
    if keep_suffix:
        return final.with_name(f".{final.stem}.{tag}-{os.getpid()}{final.suffix}")
    return final.with_name(f".{final.name}.{tag}-{os.getpid()}")


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, keep_suffix: bool = False):
    """Yield a temporary path beside `path`; rename it over `path` only if the block succeeds."""
    final = Path(path)
    final.parent.mkdir(parents=True, exist_ok=True)
    tmp = temporary_beside(final, "tmp", keep_suffix)
    try:
        yield tmp
        os.replace(tmp, final)
    finally:
        if tmp.exists():
            tmp.unlink()


def write_text_atomic(path: str | os.PathLike, text: str) -> None:
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")


def file_sha256(path: str | os.PathLike, chunk: int = 1 << 20) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        while block := f.read(chunk):
            digest.update(block)
    return digest.hexdigest()


@contextlib.contextmanager
def atomic_dir(path: str | os.PathLike, is_previous_output):
    """Yield a temporary folder beside `path` and move it to `path` on success. An existing `path` is
    replaced only if `is_previous_output(path)` says it is an earlier output of the same kind, so a
    mistyped --out never deletes someone's folder."""
    final = Path(path)
    final.parent.mkdir(parents=True, exist_ok=True)
    tmp, old = temporary_beside(final, "tmp"), temporary_beside(final, "old")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir()
    try:
        yield tmp
        if final.exists():
            if not is_previous_output(final):
                raise FileExistsError(final)
            os.replace(final, old)
        os.replace(tmp, final)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
        shutil.rmtree(old, ignore_errors=True)


# Temporaries are named `.<final name>.<tag>-<pid>[<suffix>]` (temporary_beside) or `.<tag>-<pid>-<random>`
# (temporary_dir): the pid says whether the process that made one still runs.
_TEMPORARY = re.compile(r"\..+\.(?:tmp|old)-(\d+)(?:\.[^.]*)?|\.[a-z-]+-(\d+)-[a-z0-9_]+")
_cleaned: set[Path] = set()


def clean_stale_temporaries(directory: str | os.PathLike) -> list[Path]:
    """Delete the temporaries that processes no longer running left in `directory` (after a kill -9
    or a power cut they stayed forever: issue 23). A live process's temporaries are kept, so runs
    sharing a folder do not disturb each other. Once per directory and process; returns what went."""
    directory = Path(directory).resolve()
    if directory in _cleaned or not directory.is_dir():
        return []
    _cleaned.add(directory)
    removed = []
    for entry in directory.iterdir():
        match = _TEMPORARY.fullmatch(entry.name)
        if not match or is_running(int(match.group(1) or match.group(2))):
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry, ignore_errors=True)
        else:
            entry.unlink(missing_ok=True)
        removed.append(entry)
    if removed:
        log.info("%s: removed %d temporaries of processes no longer running: %s", directory, len(removed),
                 [p.name for p in removed])
    return removed


def temporary_dir(directory: str | os.PathLike, tag: str) -> Path:
    """A new hidden folder `.<tag>-<pid>-<random>` in `directory` that clean_stale_temporaries removes
    once this process is gone (tempfile's names carry no pid)."""
    Path(directory).mkdir(parents=True, exist_ok=True)
    return Path(tempfile.mkdtemp(prefix=f".{tag}-{os.getpid()}-", dir=directory))


class WriteGuard(io.RawIOBase):
    """A file for h5py to write through (``h5py.File(WriteGuard(path), "w")``) that never reports a
    failed write to HDF5: the first OSError (disk full, file size limit) is kept, later writes are
    dropped, and ``close()`` raises it, naming the file.

    HDF5 cannot close a file whose writes failed, and then crashes the process (a segmentation fault,
    issue 23); this way HDF5 closes a file that merely holds garbage, which the caller's atomic write
    then deletes. Positioned reads and writes (pread/pwrite), so a seek cannot fail either."""

    def __init__(self, path: str | os.PathLike):
        self.name = str(path)
        self._fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_TRUNC, 0o644)
        self._pos = 0
        self.error: OSError | None = None

    def readable(self) -> bool:
        return True

    def writable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return True

    def seek(self, offset: int, whence: int = os.SEEK_SET) -> int:
        if whence == os.SEEK_END:
            offset += os.fstat(self._fd).st_size
        elif whence == os.SEEK_CUR:
            offset += self._pos
        self._pos = offset
        return offset

    def tell(self) -> int:
        return self._pos

    def readinto(self, buffer) -> int:
        data = os.pread(self._fd, len(buffer), self._pos)
        buffer[:len(data)] = data
        self._pos += len(data)
        return len(data)

    def write(self, data) -> int:
        size = memoryview(data).nbytes
        if self.error is None:
            try:
                view, at = memoryview(data).cast("B"), self._pos
                while view:
                    done = os.pwrite(self._fd, view, at)
                    view, at = view[done:], at + done
            except OSError as exc:
                self.error = exc
        self._pos += size
        return size

    def truncate(self, size: int | None = None) -> int:
        size = self._pos if size is None else size
        if self.error is None:
            try:
                os.ftruncate(self._fd, size)
            except OSError as exc:
                self.error = exc
        return size

    def flush(self) -> None:
        pass

    def close(self) -> None:
        if self.closed:
            return
        try:
            os.close(self._fd)
        finally:
            super().close()
        if self.error is not None:
            raise OSError(self.error.errno, self.error.strerror, self.name) from self.error


@contextlib.contextmanager
def guarded_h5(path: str | os.PathLike, mode: str = "w", **kwargs):
    """``h5py.File`` on a new file through a WriteGuard: a full disk raises OSError on leaving the
    block (after HDF5 has closed the file cleanly), never crashes the process."""
    import h5py

    guard = WriteGuard(path)
    try:
        with h5py.File(guard, mode, **kwargs) as f:
            yield f
    finally:
        guard.close()
