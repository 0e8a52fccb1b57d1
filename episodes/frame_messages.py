"""Messages between render processes, one pipe message per frame (episodes/render_pool.py).

A frame's arrays travel beside its pickle (protocol 5 out-of-band buffers), copied once into one block
with it, each array aligned as numpy allocates; the receiver reads the block into one writable buffer
and the arrays are views of it. Pickles cross only this pipe, in memory, between processes of one run
(as `concurrent.futures` passes its work); nothing is read back from disk this way.

Where it can, a sender puts the block in a ring of shared memory (a file in /dev/shm, mapped by both
processes) and sends through the pipe only where it lies: a pipe passes 64 KB at a time, so a block
through it costs the two processes two more copies and a system call each way per 64 KB (preview frames:
~0.5 MB, paper: ~24 MB). The receiver copies the block out at once and moves the ring's read mark,
which is all the sender waits for; so the ring's messages are read in the order they were sent, like the
pipe's. Without /dev/shm, or with too little of it, and on machines other than x86-64 (RING_MACHINES),
every block goes through the pipe; so do blocks under 64 KB and one that finds the ring full. The bytes
received are the same either way. The receiver removes the ring's file as it attaches it, so only a run
killed in between leaves one, which the next run's `remove_stale_rings` removes.
"""

from __future__ import annotations

import itertools
import logging
import mmap
import os
import pickle
import platform
import queue
import threading
import time
from pathlib import Path

import numpy as np

from episodes.processes import is_running

log = logging.getLogger(__name__)

SHM_DIR = Path("/dev/shm")
RING_PREFIX = "b2d-frames-"
RING_FRAMES = 4      # a ring holds this many blocks of the size of the first frame it was made for,
RING_MAX_BYTES = 64 << 20    # up to this (at least one block: paper frames, ~24 MB, get two)
RING_MIN_BLOCK = 64 << 10    # smaller blocks (timings, errors) go through the pipe: one pipe write each
# The read mark is a plain 8-byte store after the copy-out's loads; x86-64 keeps that order (and the
# store whole), weaker memory models need not: elsewhere every block goes through the pipe.
RING_MACHINES = {"x86_64", "AMD64"}
RING_WAIT_S = 0.005  # a block that finds the ring full waits this long for the receiver, then takes the pipe
HEADER = 64          # the ring's first bytes: the receiver's read mark (bytes ever read, int64)
PIPE, ANNOUNCE = -1, -2     # a message's first pipe part: where its block is (ring generation, or these)


class FrameSender:
    """Messages to the writer through this helper's own pipe, written by a thread so that rendering
    goes on while the writer is busy. A pipe per helper: if a helper dies mid-message, the writer
    reads end-of-file instead of waiting for the rest forever (as on a queue every helper writes to).

    Arrays travel beside the pickle (protocol 5 out-of-band buffers): a paper frame is ~24 MB, and
    pickling it whole cost ~17 ms each side where a copy costs ~3. They are copied here, at once,
    as the next capture may reuse its buffers, into one block with the pickle (in this sender's ring
    when there is room): a preview frame has ~95 arrays, and a pipe message each cost the two
    processes ~0.9 ms a frame together."""

    def __init__(self, conn, use_ring: bool = True):
        self._conn, self._queue = conn, queue.SimpleQueue()
        self.broken = False         # the writer's end closed: nothing sent from here on arrives
        self._ring: _Ring | None = None
        self._announce = False      # the ring is new: say its name before its first block
        self._use_ring = use_ring and SHM_DIR.is_dir() and platform.machine() in RING_MACHINES
        self.ring_blocks = self.pipe_blocks = 0     # where this sender's blocks went (benchmarks)
        self._thread = threading.Thread(target=self._run, name="render-helper-sender", daemon=True)
        self._thread.start()

    def send(self, *message) -> None:
        buffers: list[pickle.PickleBuffer] = []
        head = pickle.dumps(message, 5, buffer_callback=buffers.append)
        parts = [head, *(b.raw() for b in buffers)]
        sizes = np.array([part.nbytes if isinstance(part, memoryview) else len(part) for part in parts], np.int64)
        offsets = _offsets(sizes)
        total = int(offsets[-1] + sizes[-1])
        start = self._reserve(total) if self._use_ring and total >= RING_MIN_BLOCK else None
        if start is None:
            self.pipe_blocks += 1
            block = np.empty(total, np.uint8)
            _copy_parts(block, 0, parts, offsets, sizes)
            self._queue.put((np.array([PIPE, 0], np.int64).tobytes() + sizes.tobytes(), block))
            return
        self.ring_blocks += 1
        _copy_parts(self._ring.bytes, HEADER + start % self._ring.capacity, parts, offsets, sizes)
        if self._announce:      # after the copy: the receiver never waits on it
            self._queue.put((np.array([ANNOUNCE, self._ring.generation], np.int64).tobytes(), self._ring.name.encode()))
            self._announce = False
        where = np.array([self._ring.generation, start], np.int64)
        self._queue.put((where.tobytes() + sizes.tobytes(), None))

    def _reserve(self, size: int) -> int | None:
        """Where in the ring (bytes ever written) a block of `size` goes, waiting up to RING_WAIT_S for
        the receiver to read enough; None: through the pipe (no ring, none to be had, or no room)."""
        ring = self._ring
        if ring is None or (size > ring.capacity and ring.read_mark() == ring.head):
            ring = self._new_ring(size)      # the first, or a bigger one once the old one is all read
        if ring is None or size > ring.capacity:
            return None
        deadline = None
        while (start := ring.fit(size)) is None:
            now = time.monotonic()
            deadline = deadline or now + RING_WAIT_S
            if now > deadline or self.broken:
                return None
            time.sleep(0.0005)
        ring.head = _aligned(start + size)      # the next block starts aligned
        return start

    def _new_ring(self, size: int) -> "_Ring | None":
        generation = self._ring.generation + 1 if self._ring is not None else 0
        if self._ring is not None:
            self._ring.close()
            self._ring = None
        block = _aligned(size)
        capacity = block * max(1, min(RING_FRAMES, RING_MAX_BYTES // block))
        try:
            self._ring = _Ring(capacity, generation)
        except OSError as exc:     # no /dev/shm, or too little of it: the pipe carries the frames
            log.debug("frame ring of %d bytes not made (%s): frames go through the pipe", capacity, exc)
            self._use_ring = False
            return None
        self._announce = True
        return self._ring

    def _run(self) -> None:
        while (parts := self._queue.get()) is not None:
            header, block = parts
            try:
                self._conn.send_bytes(header)
                if block is not None:
                    self._conn.send_bytes(block)
            except OSError:         # the writer's process is gone
                self.broken = True
                return

    def finish(self, wait: bool = True) -> None:
        """Stop the sending thread once what is queued is sent (`wait`), or leave it (it is a daemon):
        a thread blocked on a pipe whose reader is gone never returns."""
        self._queue.put(None)
        if wait:
            self._thread.join()

    def close(self) -> None:
        self.finish()
        self._conn.close()
        self.drop_ring()

    def abandon(self) -> None:
        """Stop sending and unmap the ring, without waiting for a reader that may be gone (the pipe end
        is its owner's to close)."""
        self.finish(wait=False)
        self.drop_ring()

    def drop_ring(self) -> None:
        ring, self._ring = self._ring, None
        if ring is not None:
            ring.close()


class FrameReceiver:
    """The writer's end of one `FrameSender`: ``receive()`` reads its next message."""

    def __init__(self, reader):
        self.reader = reader
        self._ring: _Ring | None = None

    def receive(self):
        """One message: where its block is and its parts' sizes, then the block, read into one buffer
        (writable; each array aligned within it, as the arrays it becomes)."""
        header = np.frombuffer(self.reader.recv_bytes(), np.int64)
        where = int(header[0])
        if where == ANNOUNCE:
            name = self.reader.recv_bytes().decode()
            self.close()        # the old ring is all read: a sender replaces its ring only then
            self._ring = _Ring.attach(name, int(header[1]))
            return self.receive()
        sizes = header[2:]
        offsets = _offsets(sizes)
        block = np.empty(int(offsets[-1] + sizes[-1]), np.uint8)
        if where == PIPE:
            self.reader.recv_bytes_into(block)
        else:
            ring, start = self._ring, int(header[1])
            if ring is None or ring.generation != where:
                raise OSError(f"a frame in ring {where}, which this receiver has not been given")
            at = HEADER + start % ring.capacity
            block[:] = ring.bytes[at:at + len(block)]
            ring.set_read_mark(_aligned(start + len(block)))      # the sender may reuse the space up to here
        view = memoryview(block)
        head, *buffers = (view[start:start + size] for start, size in zip(offsets, sizes))
        return pickle.loads(head, buffers=buffers)

    def close(self) -> None:
        ring, self._ring = self._ring, None
        if ring is not None:
            ring.close()


_ring_numbers = itertools.count()     # rings this process has made (a ring's file name: pid, number, time)


class _Ring:
    """A shared-memory ring of message blocks: one sender writes, one receiver copies out. Positions
    count bytes ever written; a block never wraps round the end (the sender skips to the start)."""

    def __init__(self, capacity: int, generation: int, path: Path | None = None):
        self.capacity, self.generation, self.head = capacity, generation, 0
        create = path is None
        self.path = path or SHM_DIR / f"{RING_PREFIX}{os.getpid()}-{next(_ring_numbers)}-{time.monotonic_ns()}"
        fd = os.open(self.path, os.O_RDWR | (os.O_CREAT | os.O_EXCL if create else 0), 0o600)
        try:
            if create:
                try:    # allocated now: a full /dev/shm is an error here, not a SIGBUS on a later write
                    os.posix_fallocate(fd, 0, HEADER + capacity)
                except OSError:
                    os.unlink(self.path)
                    raise
            self.map = mmap.mmap(fd, HEADER + capacity)
        finally:
            os.close(fd)
        self.bytes = np.frombuffer(self.map, np.uint8)
        self._mark = self.bytes[:8].view(np.int64)

    @property
    def name(self) -> str:
        return self.path.name

    @classmethod
    def attach(cls, name: str, generation: int) -> "_Ring":
        """The receiver's mapping of a sender's ring; its file is removed at once (the two mappings keep
        the memory until both close), so a helper killed later leaves nothing in /dev/shm."""
        path = SHM_DIR / name
        if not name.startswith(RING_PREFIX) or path.parent != SHM_DIR:
            raise OSError(f"not a frame ring: {name!r}")
        ring = cls(os.path.getsize(path) - HEADER, generation, path)
        os.unlink(path)
        return ring

    def read_mark(self) -> int:
        return int(self._mark[0])

    def set_read_mark(self, value: int) -> None:
        self._mark[0] = value

    def fit(self, size: int) -> int | None:
        """Where a block of `size` can start now (after the last, or at the ring's start if it would
        wrap), or None while the receiver has not read enough."""
        start = self.head
        if start % self.capacity + size > self.capacity:
            start += self.capacity - start % self.capacity
        return start if start + size - self.read_mark() <= self.capacity else None

    def close(self) -> None:
        """Unmap. The file is the receiver's to remove as it attaches (a sender's close cannot know whether
        its announcement is still in the pipe), or `remove_stale_rings`' once the sender is gone."""
        if self.map.closed:
            return
        del self._mark, self.bytes      # the mapping closes only once no array views it
        self.map.close()


def remove_stale_rings() -> None:
    """Remove this user's rings whose sender has ended before a receiver attached them (a killed run's,
    or announced as the run ended)."""
    if not SHM_DIR.is_dir():
        return
    for path in SHM_DIR.glob(f"{RING_PREFIX}*-*"):
        try:
            if path.stat().st_uid != os.getuid():
                continue
            pid = int(path.name[len(RING_PREFIX):].split("-")[0])
        except (OSError, ValueError):
            continue
        if not is_running(pid):
            try:
                path.unlink(missing_ok=True)
            except OSError:         # another process's to remove after all: left as it is
                continue


ALIGN = 64      # each array's bytes start at a multiple of this in a message's block (as numpy allocates)


def _aligned(n: int) -> int:
    return -(-n // ALIGN) * ALIGN


def _offsets(sizes: np.ndarray) -> np.ndarray:
    """Where each part starts in a block holding them in order, every part aligned to ALIGN."""
    padded = -(-sizes // ALIGN) * ALIGN
    return np.concatenate([[0], np.cumsum(padded)[:-1]]).astype(np.int64)


def _copy_parts(target: np.ndarray, at: int, parts: list, offsets: np.ndarray, sizes: np.ndarray) -> None:
    """Copy a message's parts into the bytes `target` from byte `at`, each at its offset."""
    for part, start, size in zip(parts, offsets, sizes):
        target[at + start:at + start + size] = np.frombuffer(part, np.uint8)
