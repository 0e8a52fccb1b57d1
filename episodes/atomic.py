"""Write-then-rename, so a crash or a bad episode never leaves a half-written file behind."""

from __future__ import annotations

import contextlib
import hashlib
import os
import shutil
from pathlib import Path


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
