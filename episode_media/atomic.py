"""Write-then-rename for a whole output folder (`b2d export usd`). Single files go through
episodes.atomic.atomic_path(keep_suffix=True): OpenCV and USD choose the format from the suffix."""

from __future__ import annotations

import contextlib
import os
import shutil
from pathlib import Path

from episodes.atomic import temporary_beside


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
