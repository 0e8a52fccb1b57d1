"""Several recordings replayed into episodes on N processes (`b2d replay RAW... --workers N`).

One recording on N workers shares its frames' render between processes (episodes/render_pool.py); its
physics replay and the episode's assembly stay in one process, and sharing a frame costs a pipe copy.
Several recordings on N workers go faster whole: this process and N-1 spawned ones each take the next
recording (the longest left first) and replay, render and assemble it, so every stage runs on every core and nothing passes
between them until the end: a process with none left to take helps render the others' last recordings
(episodes/render_desk.py). Either way each episode is byte-identical to a one-worker
replay of it.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import queue
import threading
import traceback
from collections import deque
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Iterator

import h5py

from episodes.render_desk import HELP_POLL_S, MAX_PROCESSES, Desks, help_for_a_while, leave_desk, take_desk
from episodes.stages import raw_to_episode
from episodes.workers import one_core, start_worker
from sim.registry import SensorProfile
from sim.replay import DEFAULT_DRIFT_BOUND_M

Outcome = Path | Exception      # an episode written, or the error its recording met
log = logging.getLogger(__name__)


def replay_recordings(raw_paths: list[Path], profile: SensorProfile, out_dir: Path, workers: int = 1,
                      max_frames: int | None = None, drift_bound_m: float = DEFAULT_DRIFT_BOUND_M,
                      shared: dict | None = None, help_others: bool = True) -> Iterator[tuple[Path, Outcome]]:
    """``(raw path, episode path or the error it met)`` for each recording, in the order given; one that
    fails never stops the others. With ``workers`` > 1 and more than one recording, whole recordings
    run on that many processes (this one included); one recording shares its render between them.
    ``shared`` (benchmarks) gets ``frames_helped``: the frames processes with none left to take rendered
    for the others' recordings; ``help_others=False`` (benchmarks: the way before) leaves them waiting."""
    paths, out_dir = [Path(p) for p in raw_paths], Path(out_dir)
    options = {"max_frames": max_frames, "drift_bound_m": drift_bound_m}
    if workers <= 1 or len(paths) < 2:
        for path in paths:
            yield path, _replay_one(path, profile, out_dir, options, workers)
        return
    # Two recordings of one name (from different folders) make the same episode file: run at once, the
    # second would replace the first unnoticed. A later one runs once all others are done, where the
    # check that an episode is replaced only by a re-run of its own recording refuses it as in one process.
    first, seen = [], set()
    for i, path in enumerate(paths):
        if path.name not in seen:
            first.append((i, path))
        seen.add(path.name)
    done: dict[int, Outcome] = {}
    given = 0
    for i, outcome in _whole_recordings(first, profile, out_dir, options, min(workers, len(first)), shared,
                                        help_others):
        done[i] = outcome
        while given in done:            # in the order given, as soon as each is ready
            yield paths[given], done.pop(given)
            given += 1
    for i in range(given, len(paths)):
        yield paths[i], done.pop(i) if i in done else _replay_one(paths[i], profile, out_dir, options, 1)


def _whole_recordings(items: list[tuple[int, Path]], profile: SensorProfile, out_dir: Path, options: dict,
                      processes: int, shared: dict | None = None,
                      help_others: bool = True) -> Iterator[tuple[int, Outcome]]:
    """``(index, outcome)`` of each item as it finishes: this process and ``processes`` - 1 spawned ones
    take the next recording from one queue; a process with none left to take helps render the others'
    (episodes/render_desk.py). A spawned process that dies (out of memory, a crash in a native library)
    fails the recordings it was given; this one takes the rest."""
    waiting, lock, finished = deque(longest_first(items)), threading.Lock(), queue.SimpleQueue()
    helped: dict[int, int] = {}     # per spawned process: the frames it has rendered for the others so far

    def take() -> tuple[int, Path] | None:
        with lock:
            return waiting.popleft() if waiting else None

    def feed(pool: ProcessPoolExecutor) -> None:
        while (item := take()) is not None:
            try:
                future = pool.submit(_replay_one, item[1], profile, out_dir, options, 1)
            except RuntimeError:         # the pool is broken or shut down: the item is left for this process
                with lock:
                    waiting.appendleft(item)
                finished.put(None)       # wakes this process to take it
                return
            try:
                finished.put((item[0], future.result()))
            except BrokenProcessPool as exc:
                finished.put((item[0], RuntimeError(
                    f"a worker process ended abruptly while this recording or another was replayed ({exc}); "
                    "replay it again, with --workers 1 to find the recording at fault")))
            except Exception as exc:     # e.g. a result that could not be passed back
                finished.put((item[0], exc))
        # nothing left to take: the process this feeder fed helps the others' renders, in short calls so
        # that the pool can shut down whenever the batch ends (or the interpreter exits)
        while desks is not None and not desks.finished.value:
            try:
                pid, frames = pool.submit(help_for_a_while).result()
            except Exception:        # a broken pool: the recordings it had report it; helping costs only time
                log.debug("a spawned process stopped helping", exc_info=True)
                return
            helped[pid] = frames

    ctx = multiprocessing.get_context("spawn")
    desks = Desks(ctx, processes) if help_others and processes <= MAX_PROCESSES else None
    pool, given = None, 0
    try:
        if desks is not None:
            take_desk(desks, 0)      # this process's renders are open to help too
        pool = ProcessPoolExecutor(processes - 1, mp_context=ctx, initializer=_start_replay_worker,
                                   initargs=(os.getpid(), desks))
        feeders = [threading.Thread(target=feed, args=(pool,), name=f"replay-feeder-{k}", daemon=True)
                   for k in range(processes - 1)]
        one_core()       # this process is one of the workers too (its rendering stays on one core from here on)
        for feeder in feeders:
            feeder.start()
        while given < len(items):
            item = take()
            if item is not None:
                finished.put((item[0], _replay_one(item[1], profile, out_dir, options, 1)))
            # what is done so far; with nothing left to take, help the spawned processes' renders while
            # waiting for what they have in hand
            while given < len(items) and (item is None or not finished.empty()):
                if item is None and finished.empty() and desks is not None and desks.help_one(0):
                    continue
                try:
                    result = finished.get(timeout=HELP_POLL_S if item is None and desks else None)
                except queue.Empty:
                    continue
                if result is None:       # a recording handed back: take it
                    break
                given += 1
                yield result
    finally:
        with lock:                       # abandoned early: nothing more is started
            waiting.clear()
        if desks is not None:
            desks.finished.value = 1     # helping processes stop
        if pool is not None:
            pool.shutdown(wait=given == len(items), cancel_futures=True)
        if desks is not None:
            leave_desk()
        if shared is not None:
            shared["frames_helped"] = (desks.frames_helped if desks else 0) + sum(helped.values())


def longest_first(items: list[tuple[int, Path]]) -> list[tuple[int, Path]]:
    """The recordings by their number of control steps, longest first (equal ones in the order given): the
    batch's last work, which no other process can share (a recording's physics replay and its assembly),
    is then a short recording's. One that cannot be read goes last, to fail in its turn."""
    def steps(path: Path) -> int:
        try:
            with h5py.File(path, "r") as f:
                return int(f["action"].shape[0])
        except Exception:
            return -1
    return sorted(items, key=lambda item: -steps(item[1]))


def _start_replay_worker(parent_pid: int, desks: Desks | None) -> None:
    """A spawned process's start: it dies with this one, renders on one core and posts its renders at
    its desk."""
    start_worker(parent_pid, one_core)
    if desks is not None:
        take_desk(desks)


def _replay_one(path: Path, profile: SensorProfile, out_dir: Path, options: dict, workers: int) -> Outcome:
    """One recording's episode, or the error it met (with its traceback as text: an error crossing a
    process boundary loses its own)."""
    try:
        return raw_to_episode(path, profile, out_dir, workers=workers, **options)
    except Exception as exc:     # one bad recording never stops the others
        exc.worker_traceback = traceback.format_exc()
        return exc
