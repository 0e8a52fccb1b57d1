"""Whether a process still runs, by its pid: what the stale-file sweeps (temporaries, frame rings) and
the batch's render desks ask of a process they share work or files with."""

from __future__ import annotations

import os


def is_running(pid: int) -> bool:
    """Whether process `pid` runs. A child that has died stays a zombie until its parent reaps it: that
    counts as ended. Another user's process counts as running (it cannot be signalled, but it is there)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except (ProcessLookupError, OverflowError):     # gone, or no pid at all
        return False
    except PermissionError:
        return True
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            return f.read().rsplit(b")", 1)[1].split()[0] != b"Z"
    except (OSError, IndexError):        # no /proc (not Linux): taken as running
        return True
