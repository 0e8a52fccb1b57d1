"""Helper processes that render an episode's frames beside the process that writes them (issue 22).

A render with N workers runs in the calling process and N-1 helpers. Every renderer takes the next
frame index from one shared counter, so the frames split themselves by speed (the writing process,
which also compresses and writes every frame, simply takes fewer); helpers send their frames to the
caller, which writes all frames in order through the one-worker writer. The render file is therefore
byte-identical to a one-worker render, and nothing is joined afterwards (joining parts cost ~1.4 s
and a writer per part; each worker's start-up ~3 CPU-seconds).

Helpers are spawned once per process and kept across render calls, so their imports and GL start-up
are paid once. A render does not wait for them to start: it hands them its frames' counter at once and
renders alone until they are ready, so a short render in a fresh process (an executor's step, one
`b2d replay`) is never slower than one worker by their start-up (~1.5 CPU-seconds each). Each call builds the episode's scene and renderer in every helper it uses: a scene
depends on the episode's scene sample (textures, lights, distractors, camera offsets), so there is
nothing valid to keep between two episodes of one setting.

Frames cross the process boundary through a pipe per helper, pickled in memory with their arrays
beside the pickle (episodes/frame_messages.py); nothing is read back from disk this way.
"""

from __future__ import annotations

import atexit
import logging
import multiprocessing
import multiprocessing.connection
import os
import threading
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import numpy as np

from episodes.frame_messages import FrameReceiver, FrameSender, remove_stale_rings
from episodes.workers import die_with_parent, one_core

log = logging.getLogger(__name__)

MAX_AHEAD = 8        # frames a renderer may start beyond the last one written (bounds the frames held in memory)
WAIT_S = 0.002       # a helper held back by MAX_AHEAD looks again after this
POLL_S = 1.0         # the writer checks that its helpers still live at this interval while it waits
DRAIN_S = 60.0       # a helper that sends nothing for this long at a job's end is given up
JOB, NEXT, TOTAL, WRITTEN, JOINED = range(5)     # the shared counters (JOINED: a bit per helper)
STATE_SLOTS = 5
MAX_HELPERS = 62     # JOINED is an int64


def _take(lock, state, job: int, max_ahead: int, helper: int | None = None) -> int | None:
    """The next frame index of `job` for the calling renderer, or None when it has none left (or the
    job ended); -1 when every index left is more than `max_ahead` beyond the last frame written.
    A helper (`helper`: its index) joins the job with the first frame it takes: the writer waits at
    the end for the helpers that joined, and only for them."""
    with lock:
        if state[JOB] != job or state[NEXT] >= state[TOTAL]:
            return None
        i = state[NEXT]
        if i >= state[WRITTEN] + max_ahead:
            return -1
        state[NEXT] = i + 1
        if helper is not None:
            state[JOINED] |= 1 << helper
        return i


# ---------------------------------------------------------------- helper process


def _helper_main(index: int, tasks, conn, lock, state, parent_pid: int, max_ahead: int) -> None:
    die_with_parent(parent_pid)
    one_core()      # one helper is meant for one core
    out = FrameSender(conn)
    _warm_gl()
    # this process's CPU seconds so far: interpreter, the imports spawn repeats (the parent's main
    # module's too), GL start-up
    out.send("ready", index, 0, None, time.process_time())
    while (task := tasks.get()) is not None:
        help_render(task, index, out, lock, state, max_ahead)
    out.close()


def help_render(task: tuple, index: int, out: FrameSender, lock, state, max_ahead: int,
                still_wanted=lambda: True) -> int:
    """Render frames of the job `task` (job id, replay path, profile, steps) as helper `index`, taking
    them from the shared counter and sending them through `out`, until none is left; then its timings.
    A job that ended before its scene was built is skipped without a word (the writer waits only for
    helpers that took a frame). `still_wanted()` is asked while the writer holds this helper back: False
    gives up (the writer's process is gone, or it has written nothing for a long while); the frames
    sent so far and the helper's end still reach the writer. Returns the number of frames rendered."""
    from episodes.replay_frames import ReplayFrames

    job, replay_path, profile, steps = task
    cpu = time.process_time()
    if state[JOB] != job:         # the writer finished without us: no scene to build
        return 0
    try:
        frames = ReplayFrames(Path(replay_path), profile, steps)
    except BaseException as exc:     # reported to the writer, which renders this helper's share itself
        out.send("error", index, job, None, f"{type(exc).__name__}: {exc}")
        return 0
    setup_cpu, first, count, piped = time.process_time() - cpu, time.time(), 0, out.pipe_blocks
    try:
        while (i := _take(lock, state, job, max_ahead, index)) is not None:
            if i < 0:
                if not still_wanted():
                    break
                time.sleep(WAIT_S)
                continue
            out.send("frame", index, job, i, frames.capture(i))
            count += 1
    except BaseException as exc:
        out.send("error", index, job, None, f"{type(exc).__name__}: {exc}")
        return count
    finally:
        frames.close()
    if count:
        out.send("done", index, job, None, {
            "frames": count, "seconds": frames.seconds(), "frame_windows": [(first, time.time())],
            "setup_cpu_s": setup_cpu, "cpu_s": time.process_time() - cpu,
            "frames_through_pipe": out.pipe_blocks - piped})      # not through the shared-memory ring
    return count


def _warm_gl() -> None:
    """Make and drop one tiny GL context, so the display and driver start-up is not paid by the
    first episode."""
    try:
        import mujoco

        from sim.offscreen import OffscreenRenderer

        model = mujoco.MjModel.from_xml_string(
            '<mujoco><worldbody><light pos="0 0 2"/><camera name="c" pos="0 0 1"/><geom size="0.1"/>'
            '</worldbody></mujoco>')
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        renderer = OffscreenRenderer(model, 8, 8)
        try:
            renderer.update(data, 0)
            renderer.depth_and_geoms(True)
        finally:
            renderer.close()
    except Exception:       # only a warm-up: the first real renderer reports any real failure
        log.debug("render helper GL warm-up failed", exc_info=True)


# ---------------------------------------------------------------- writer side


class HelperChannels:
    """The writer's side of `count` helpers: the shared counters, a frame pipe per helper, and the jobs
    handed to them. Who the helpers are, and how a job reaches them, is the subclass's: processes this
    one spawned (RenderHelpers), or a batch's processes with nothing left to do (episodes/render_desk.py)."""

    def __init__(self, count: int, max_ahead: int, lock, state, readers: list):
        if count > MAX_HELPERS:
            raise ValueError(f"render helpers: expected at most {MAX_HELPERS}, got {count}")
        self.count, self.max_ahead = count, max_ahead
        self._lock, self._state, self._readers = lock, state, readers
        self._lost: set[int] = set()     # helpers whose pipe ended or broke
        self._receivers: dict = {}         # per reader: its FrameReceiver (the sender's ring, once it has one)
        self._jobs = 0
        self._busy = threading.Lock()

    def _helper_alive(self, k: int) -> bool:
        raise NotImplementedError

    def _hand_out(self, task: tuple, helpers: set[int]) -> None:
        """Give `task` (job id, replay path, profile, steps) to `helpers`."""
        raise NotImplementedError

    @contextmanager
    def job(self, replay_path: Path, profile, steps: np.ndarray, helpers: int):
        """Hand the frames of `steps` to up to `helpers` helpers; yields a `_Job` (None when another
        thread's render is using them: render alone then). The helpers start building their scene
        at once, while the caller builds its own."""
        if not self._busy.acquire(blocking=False):
            yield None
            return
        try:
            self._jobs += 1
            job = _Job(self, self._jobs, len(steps))
            with self._lock:
                self._state[:] = [job.id, 0, len(steps), 0, 0]
            job.open = {k for k in range(min(helpers, self.count)) if k not in self._lost and self._helper_alive(k)}
            if job.open:
                self._hand_out((job.id, str(replay_path), profile, np.asarray(steps)), job.open)
            try:
                yield job
            finally:
                with self._lock:
                    self._state[JOB] = 0      # helpers stop taking this job's frames
        finally:
            self._busy.release()

    def _receive(self, helpers: set[int], job: int, pending: dict, stats: list, timeout: float) -> bool:
        """Read every message waiting from `helpers` (after up to `timeout` s for the first); frames
        of `job` go to `pending`, its helpers' final timings to `stats` (and out of `helpers`). False
        when one of them failed or died."""
        readers = {self._readers[k]: k for k in helpers if k not in self._lost}
        if len(readers) < len(helpers):
            return False
        ready = multiprocessing.connection.wait(list(readers), timeout)
        if not ready:
            return all(self._helper_alive(k) for k in helpers)
        ok = True
        for reader in ready:
            k = readers[reader]
            try:
                while reader.poll():
                    ok &= self._handle(self._receiver(reader).receive(), job, pending, helpers, stats)
            except (EOFError, OSError):        # it died, perhaps mid-message
                self._lost.add(k)
                helpers.discard(k)
                ok = False
        return ok

    def _receiver(self, reader) -> FrameReceiver:
        receiver = self._receivers.get(reader)
        if receiver is None:
            receiver = self._receivers[reader] = FrameReceiver(reader)
        return receiver

    def close_receivers(self) -> None:
        """Unmap the helpers' rings (their pipes are the caller's to close)."""
        for receiver in self._receivers.values():
            receiver.close()
        self._receivers.clear()

    def _handle(self, message, job: int, pending: dict, helpers: set, stats: list) -> bool:
        kind, helper, of_job, i, payload = message
        if kind == "ready":
            self._ready(helper, payload)
        elif of_job != job:
            pass                              # left over from an earlier job
        elif kind == "frame":
            pending.setdefault(i, payload)
        elif kind == "done":
            helpers.discard(helper)
            stats.append(payload)
        elif kind == "error":
            helpers.discard(helper)
            log.warning("render helper %d failed; the writing process renders its frames: %s", helper, payload)
            return False
        return True

    def _ready(self, helper: int, startup_cpu_s: float) -> None:
        pass


class RenderHelpers(HelperChannels):
    """`count` helper processes, started now and kept until `close()`."""

    def __init__(self, count: int, max_ahead: int = MAX_AHEAD):
        if count < 1:
            raise ValueError(f"render helpers: expected at least 1, got {count}")
        ctx = multiprocessing.get_context("spawn")   # a forked child would inherit GL and h5py state
        self.owner = os.getpid()
        remove_stale_rings()        # of helpers killed before their frames were read (a killed run's)
        super().__init__(count, max_ahead, ctx.Lock(), ctx.RawArray("q", STATE_SLOTS), [])
        self._tasks = [ctx.SimpleQueue() for _ in range(count)]
        self._procs = []
        for k in range(count):
            reader, writer = ctx.Pipe(duplex=False)
            self._procs.append(ctx.Process(target=_helper_main, name=f"b2d-render-helper-{k}", daemon=True,
                                           args=(k, self._tasks[k], writer, self._lock, self._state, os.getpid(),
                                                 max_ahead)))
            self._procs[-1].start()
            writer.close()      # the helper's end only: its death is then end-of-file here
            self._readers.append(reader)
        self.startup_cpu_s: dict[int, float] = {}     # per helper: CPU seconds of its start (imports, GL)

    def _helper_alive(self, k: int) -> bool:
        return self._procs[k].is_alive()

    def _hand_out(self, task: tuple, helpers: set[int]) -> None:
        for k in helpers:
            self._tasks[k].put(task)

    def alive(self) -> bool:
        return not self._lost and all(p.is_alive() for p in self._procs)

    def ready(self, k: int) -> bool:
        """Whether helper `k` has said it started (imports, GL): one still starting takes no frames yet."""
        return k in self.startup_cpu_s

    def _ready(self, helper: int, startup_cpu_s: float) -> None:
        self.startup_cpu_s[helper] = startup_cpu_s

    def wait_ready(self, timeout: float = 120.0) -> dict[int, float]:
        """Block until every helper has started (imports, GL); their start-up CPU seconds."""
        deadline = time.monotonic() + timeout
        while len(self.startup_cpu_s) < self.count:
            if time.monotonic() > deadline or not self._receive(set(range(self.count)), 0, {}, [], POLL_S):
                raise RuntimeError(f"render helpers: {self.count - len(self.startup_cpu_s)} of {self.count} "
                                   f"did not start within {timeout:.0f} s")
        return dict(self.startup_cpu_s)

    def close(self) -> None:
        for p, tasks in zip(self._procs, self._tasks):
            if p.is_alive():
                try:
                    tasks.put(None)
                except (OSError, ValueError):
                    pass
        for p in self._procs:
            p.join(timeout=5)
            if p.is_alive():
                p.kill()
                p.join(timeout=5)
        self.close_receivers()
        for reader in self._readers:
            reader.close()


class _Job:
    def __init__(self, helpers: HelperChannels, job_id: int, total: int):
        self.helpers, self.id, self.total = helpers, job_id, total
        self.open: set[int] = set()       # helpers handed the job that have not reported its end
        self.stats: list[dict] = []

    def in_order(self, local) -> Iterator[tuple[dict, bool]]:
        """Every frame as (datasets, has error), in index order: the caller's own renderer `local`
        (a ReplayFrames) renders its share, helpers the rest. Should a helper fail or die, the
        caller renders whatever has not arrived (the same frames, only slower). However it ends (the
        last frame, an error, the generator closed early), the helpers that took part are read to
        their end, so that none is left blocked on a full pipe."""
        h, pending, written, alone = self.helpers, {}, 0, not self.open
        try:
            while written < self.total:
                if not alone and self.open:
                    alone = not h._receive(self.open, self.id, pending, self.stats, 0)
                if written in pending:
                    yield pending.pop(written)
                    written += 1
                    with h._lock:
                        h._state[WRITTEN] = written
                    continue
                if alone:
                    pending[written] = local.capture(written)
                    continue
                i = _take(h._lock, h._state, self.id, h.max_ahead)
                if i is not None and i >= 0:
                    pending[i] = local.capture(i)
                elif not self.open:
                    alone = True      # a frame taken by a helper that has ended or failed: ours now
                else:
                    alone = not h._receive(self.open, self.id, pending, self.stats, POLL_S)
                if alone:
                    with h._lock:
                        h._state[JOB] = 0       # the others stop too; what is missing is rendered here
        finally:
            self._hear_the_end()

    def _hear_the_end(self) -> None:
        """End the job and read every helper that took part to its end (their timings, for benchmarks;
        they end within a frame). One that took no frame (not started, or busy elsewhere) is not waited
        for; one silent for DRAIN_S is given up (lost: its pipe may hold half a message)."""
        h = self.helpers
        with h._lock:
            h._state[JOB] = 0       # a helper that has not started building its scene skips the job
            joined = h._state[JOINED]
        self.open = {k for k in self.open if joined >> k & 1}
        heard = time.monotonic()
        while self.open:
            frames, waiting = {}, len(self.open)
            h._receive(self.open, self.id, frames, self.stats, POLL_S)     # frames dropped: all are written
            if frames or len(self.open) < waiting:
                heard = time.monotonic()
            elif time.monotonic() - heard > DRAIN_S:
                h._lost.update(self.open)
            self.open = {k for k in self.open if k not in h._lost and h._helper_alive(k)}


# ---------------------------------------------------------------- one set per process

_shared: RenderHelpers | None = None
_shared_lock = threading.Lock()


def shared_helpers(count: int, wait: bool = True) -> RenderHelpers:
    """This process's helpers (at least `count`), started on first use and kept until it exits; a
    set with a dead helper (killed, or its starting thread ended: the kernel then ends it) is
    replaced. `wait`: block until new helpers have started (benchmarks time their start apart);
    a render need not, its helpers join it when ready."""
    global _shared
    with _shared_lock:
        pool = _shared
        if pool is not None and pool.owner != os.getpid():
            pool = None       # inherited through fork: another process's helpers
        if pool is not None and (pool.count < count or not pool.alive()):
            pool.close()
            pool = None
        _shared = None
        if pool is None:
            pool = RenderHelpers(count)
            try:
                if wait:
                    pool.wait_ready()     # their imports and GL start-up, once: then every call finds them warm
            except BaseException:
                pool.close()
                raise
        _shared = pool
        return pool


@atexit.register
def close_shared_helpers() -> None:
    global _shared
    with _shared_lock:
        if _shared is not None and _shared.owner == os.getpid():
            _shared.close()
        _shared = None
