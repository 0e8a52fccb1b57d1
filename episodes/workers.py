"""Worker processes that do not outlive the process that started them, and a map over them.

A parallel render's workers kept rendering after their parent was killed (issue 23). On Linux the
kernel sends a signal to a process whose parent dies, once it asks with prctl(PR_SET_PDEATHSIG);
elsewhere a daemon thread polls the parent's pid.
"""

from __future__ import annotations

import ctypes
import multiprocessing
import os
import signal
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from typing import Callable, Iterable, Iterator

PR_SET_PDEATHSIG = 1
POLL_S = 1.0


def die_with_parent(parent_pid: int) -> None:
    """Pool initializer: end this process (SIGKILL) when `parent_pid` ends."""
    if sys.platform.startswith("linux"):
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) != 0:
            _watch(parent_pid)
    else:
        _watch(parent_pid)
    if os.getppid() != parent_pid:      # the parent went before the request was made
        os._exit(1)


def _watch(parent_pid: int) -> None:
    def poll() -> None:
        while os.getppid() == parent_pid:
            time.sleep(POLL_S)
        os._exit(1)

    threading.Thread(target=poll, name="die-with-parent", daemon=True).start()


def one_core() -> None:
    """Keep this process's rendering on one core, for a process meant for one of several cores: Mesa's
    software GL rasterizes on the calling thread (its default, a thread per core in every process,
    oversubscribes the cores), OpenCV on one. Neither changes a byte. Before the first GL context."""
    os.environ.setdefault("LP_NUM_THREADS", "0")
    import cv2

    cv2.setNumThreads(1)


def start_worker(parent_pid: int, on_start: Callable | None = None) -> None:
    """Pool initializer: die with the process ``parent_pid``, then run ``on_start()``."""
    die_with_parent(parent_pid)
    if on_start is not None:
        on_start()


def map_in_processes(fn: Callable, arguments: Iterable[tuple], processes: int,
                     on_start: Callable | None = None) -> Iterator:
    """``fn(*args)`` for each of ``arguments``, yielded in their order; with ``processes`` > 1 in that many
    spawned processes that die with this one and first run ``on_start()`` (``fn`` and ``on_start`` must be
    module-level functions), else here."""
    if processes <= 1:
        for args in arguments:
            yield fn(*args)
        return
    with ProcessPoolExecutor(processes, mp_context=multiprocessing.get_context("spawn"),
                             initializer=start_worker, initargs=(os.getpid(), on_start)) as pool:
        futures = [pool.submit(fn, *args) for args in arguments]
        for future in futures:
            yield future.result()
