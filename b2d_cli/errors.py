"""Every error a command meets becomes one line naming the input and the fault (issue 23).

Exit status: 2 for bad input (a file, a name or a value the command refuses), 1 for a fault of the
machine (disk full, permissions) or of b2d itself. `B2D_TRACEBACK=1` shows the traceback as well.
"""

from __future__ import annotations

import errno
import os
import re
import sys
from pathlib import Path

import click

BAD_INPUT, FAULT = 2, 1
_DISK_FULL = {errno.ENOSPC, errno.EFBIG, errno.EDQUOT}


def is_bad_input(exc: BaseException) -> bool:
    """ValueError (SpecError, JSON, numpy), KeyError (UnknownNameError), TypeError: the input's fault."""
    return isinstance(exc, (ValueError, LookupError, TypeError)) and not isinstance(exc, UnicodeEncodeError)


def exit_code(exc: BaseException) -> int:
    return BAD_INPUT if is_bad_input(exc) else FAULT


def one_line(exc: BaseException, subject: str | Path | None = None) -> str:
    """`<subject>: <fault>` on one line; the subject is left out when the message names it already."""
    if is_disk_full(exc):
        named = getattr(exc, "filename", None) or re.search(r"filename = '([^']+)'", str(exc))
        target = named.group(1) if isinstance(named, re.Match) else named
        text = f"no space left writing {target}" if target else "no space left to write the output"
        return (f"{subject}: " if subject else "") + f"{text} (disk full or over the file size limit)"
    message = " ".join(str(exc).split()) or "(no message)"
    from sim.errors import SpecError, UnknownNameError

    if not isinstance(exc, (SpecError, UnknownNameError)):
        message = f"{type(exc).__name__}: {message}"
    if subject is not None and str(subject) not in message:
        message = f"{subject}: {message}"
    return message[:2000]


def message(exc: BaseException) -> str:
    """What a command prints for an error: the project's own errors as written (a schema's findings keep
    one per line), anything else on one line."""
    from sim.errors import SpecError, UnknownNameError

    if isinstance(exc, (SpecError, UnknownNameError)) and not is_disk_full(exc):
        return str(exc)
    return one_line(exc)


def report_batch(action: str, total: int, failed: list[tuple[str | Path, BaseException]]) -> None:
    """The summary of a batch command, on stderr, and its exit (nothing when all went well)."""
    if not failed:
        return
    click.echo(f"{len(failed)} of {total} {action} failed:", err=True)
    for subject, exc in failed:
        click.echo(f"  - {one_line(exc, subject)}", err=True)
    leave(max(exit_code(exc) for _, exc in failed), [exc for _, exc in failed])


def is_disk_full(exc: BaseException) -> bool:
    for e in _chain(exc):
        # HDF5's own errors carry the errno inside the message ("... errno = 28, error message = ...")
        code = e.errno if isinstance(e, OSError) and e.errno else re.search(r"errno = (\d+)", str(e))
        if (int(code.group(1)) if isinstance(code, re.Match) else code) in _DISK_FULL:
            return True
    return False


def _chain(exc: BaseException | None):
    while exc is not None:
        yield exc
        exc = exc.__cause__ or exc.__context__


def leave(code: int, errors: list[BaseException]) -> None:
    """Exit with `code`. After a write that failed for lack of space HDF5 keeps the file half closed,
    and its exit handler then crashes the process (a segmentation fault instead of the message just
    printed): leave without running it. Temporary files are already removed by then (episodes/atomic.py)."""
    if any(is_disk_full(e) for e in errors):
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


def show_traceback() -> bool:
    return os.environ.get("B2D_TRACEBACK", "") not in ("", "0")
