"""A batch's process with no recording left to take helps render the others' (issue 22 item 3).

`b2d replay RAW... --workers N` replays whole recordings on N processes (episodes/replay_batch.py). Near a
batch's end a process with nothing left to take used to wait while another still rendered its last
recording: on a short batch that tail was most of the loss (6 recordings on two cores: 1.63x one worker).
So every process of a batch has a desk where it posts each render it starts, and a process with nothing
left to take helps the posted render with the most frames left, as a render helper does
(episodes/render_pool.py). The render's own process still writes every frame in order, so each episode
stays byte-identical to a one-worker replay; a render nobody helps is rendered alone, as before.

Processes are numbered 0 (the batch's own) to N-1; on a desk, the helper slots are the other processes'.
Each process keeps only the pipe ends it uses (its own desk's readers, its slot's writer on the others'),
so a process that dies is end-of-file to every process it was sending to.
"""

from __future__ import annotations

import os
import pickle
import time

from episodes.frame_messages import FrameSender, remove_stale_rings
from episodes.processes import is_running
from episodes.render_pool import JOB, MAX_AHEAD, NEXT, STATE_SLOTS, TOTAL, WRITTEN, HelperChannels, help_render

MAX_PROCESSES = 8        # desks cost 2 N (N - 1) pipe ends in the batch's process; on more, the tail matters less
MIN_FRAMES_LEFT = 8      # fewer left: building a scene to help costs more than it saves
STALL_S = 30.0           # held back this long with no frame written: give up helping that render
HELP_POLL_S = 0.02       # a process with nothing left looks for a render to help this often
HELP_SLICE_S = 1.0       # a spawned process helps in calls of about this long (its pool can then shut down)


class Posted:
    """The latest render a process started (job id, replay path, profile, steps), kept in shared memory:
    posting never blocks (a queue's pipe fills while the others are busy with their own recordings) and
    only the latest one matters."""

    CAPACITY = 1 << 18      # bytes (~32,000 frames' steps); a render that does not fit renders alone

    def __init__(self, ctx):
        self._bytes, self._length, self._lock = ctx.RawArray("B", self.CAPACITY), ctx.RawValue("q", 0), ctx.Lock()

    def put(self, task: tuple) -> None:
        data = pickle.dumps(task, pickle.HIGHEST_PROTOCOL)
        with self._lock:
            if len(data) > self.CAPACITY:
                self._length.value = 0
                return
            memoryview(self._bytes).cast("B")[:len(data)] = data
            self._length.value = len(data)

    def get(self) -> tuple | None:
        with self._lock:
            data = memoryview(self._bytes).cast("B")[:self._length.value].tobytes()
        return pickle.loads(data) if data else None      # written by a process of this batch, in memory


class Desk:
    """One process's desk: the shared counters of its renders, the render it last started, and a pipe per
    helper slot for the frames rendered for it."""

    def __init__(self, ctx, slots: int):
        self.lock, self.state = ctx.Lock(), ctx.RawArray("q", STATE_SLOTS)
        self.posted = Posted(ctx)
        pipes = [ctx.Pipe(duplex=False) for _ in range(slots)]
        self.readers, self.writers = [r for r, _ in pipes], [w for _, w in pipes]
        self.owner = ctx.RawValue("q", 0)              # the process whose renders these are
        self.helper_pids = ctx.RawArray("q", slots)    # each slot's process, once it has helped
        # a helping process's own view: its sender (one for the batch: a pipe takes one writer), the last
        # job it helped (never joined twice: the writer stops reading a helper that has ended), and the last
        # task it read (read again only for a new job: idle processes look every HELP_POLL_S)
        self._sender: FrameSender | None = None
        self._helped = 0
        self._task: tuple | None = None

    def render_to_help(self) -> tuple[int, tuple | None]:
        """(frames not yet taken, the task) of the render under way that this process may still help."""
        with self.lock:
            job, left = self.state[JOB], int(self.state[TOTAL] - self.state[NEXT])
        if not job or job == self._helped or (self._sender is not None and self._sender.broken):
            return 0, None
        if self._task is None or self._task[0] != job:
            self._task = self.posted.get()      # posted just after the counters were set: maybe not yet
        if self._task is None or self._task[0] != job or not is_running(self.owner.value):
            return 0, None
        return left, self._task

    def help(self, slot: int, task: tuple) -> int:
        """Render frames of `task` as helper `slot` until none is left (or its writer stalls for STALL_S);
        the number rendered."""
        self.helper_pids[slot] = os.getpid()
        if self._sender is None:
            self._sender = FrameSender(self.writers[slot])
        self._helped = task[0]
        written, since = -1, time.monotonic()

        def still_wanted() -> bool:      # asked while the render's process holds this one back
            nonlocal written, since
            if self._sender.broken or not is_running(self.owner.value):
                return False
            if self.state[WRITTEN] != written:
                written, since = self.state[WRITTEN], time.monotonic()
            return time.monotonic() - since < STALL_S

        return help_render(task, slot, self._sender, self.lock, self.state, MAX_AHEAD, still_wanted)

    def drop_sender(self) -> None:
        """Stop helping this desk for good: the sender's ring unmapped, its thread left to end (its reader
        may be gone)."""
        if self._sender is not None:
            self._sender.abandon()
            self._sender = None

    def keep_ends(self, mine: bool, slot: int | None) -> None:
        """Close the pipe ends this process does not use: on its own desk (`mine`) it only reads; on
        another's it writes through its `slot` only."""
        for k, (reader, writer) in enumerate(zip(self.readers, self.writers)):
            if mine:
                writer.close()
            else:
                reader.close()
                if k != slot:
                    writer.close()


class Desks:
    """The desks of a batch's `processes` processes, made by process 0 and handed to the others as they
    start."""

    def __init__(self, ctx, processes: int):
        if not 2 <= processes <= MAX_PROCESSES:
            raise ValueError(f"render desks: expected 2 to {MAX_PROCESSES} processes, got {processes}")
        self.processes = processes
        remove_stale_rings()        # of processes killed before their frames were read (a killed run's)
        self.desks = [Desk(ctx, processes - 1) for _ in range(processes)]
        self.claimed, self.claim_lock = ctx.RawValue("i", 1), ctx.Lock()
        self.finished = ctx.RawValue("b", 0)      # the batch has ended: helping processes stop
        self.frames_helped = 0                    # by this process
        self._ends_kept = False

    def keep_own_ends(self, me: int) -> None:
        """Process `me` keeps only the pipe ends it uses; process 0 once every spawned one holds its own
        (their ends cross as they start)."""
        if self._ends_kept or (me == 0 and self.claimed.value < self.processes):
            return
        for d, desk in enumerate(self.desks):
            desk.keep_ends(d == me, None if d == me else _slot(me, d))
        self._ends_kept = True

    def help_one(self, me: int) -> bool:
        """Help the others' render with the most frames left, if one has enough left to be worth a scene;
        False when none has."""
        self.keep_own_ends(me)
        most, desk, task = 0, None, None
        for d in range(self.processes):
            left, posted = self.desks[d].render_to_help() if d != me else (0, None)
            if left > most:
                most, desk, task = left, d, posted
        if most < MIN_FRAMES_LEFT:
            return False
        self.frames_helped += self.desks[desk].help(_slot(me, desk), task)
        return True

    def help_for(self, me: int, seconds: float) -> int:
        """Help the others' renders for about `seconds` (a render under way is helped to its end), or until
        the batch has ended; the frames rendered for them so far."""
        end = time.monotonic() + seconds
        while not self.finished.value and time.monotonic() < end:
            if not self.help_one(me):
                time.sleep(HELP_POLL_S)
        return self.frames_helped


def _slot(me: int, desk: int) -> int:
    """Process `me`'s helper slot on process `desk`'s desk (a desk has a slot for each other process)."""
    return me if me < desk else me - 1


class StandbyHelpers(HelperChannels):
    """A process's side of its own desk: the batch's other processes as its render helpers, each joining a
    render only once it has nothing left of its own (until then the render runs alone, as before)."""

    def __init__(self, desk: Desk):
        desk.owner.value = os.getpid()
        super().__init__(len(desk.readers), MAX_AHEAD, desk.lock, desk.state, desk.readers)
        self.desk = desk

    def _helper_alive(self, k: int) -> bool:
        pid = self.desk.helper_pids[k]
        return pid == 0 or is_running(pid)      # one that never helped has no frame of ours

    def _hand_out(self, task: tuple, helpers: set[int]) -> None:
        self.desk.posted.put(task)          # one post for every slot: whichever process is idle takes it up


# this process's place in a batch (the desks cross to a spawned process only as it starts: shared locks
# and counters cannot be pickled later)
_desks: Desks | None = None
_me: int | None = None
_standby: StandbyHelpers | None = None


def take_desk(desks: Desks, me: int | None = None) -> int:
    """Make this process one of the batch's: process `me`, or the next unnumbered one (a spawned process
    as it starts). Its renders post at its desk from now on; its number."""
    global _desks, _me, _standby
    if me is None:
        with desks.claim_lock:
            me = desks.claimed.value
            desks.claimed.value += 1
    _desks, _me, _standby = desks, me, StandbyHelpers(desks.desks[me])
    desks.keep_own_ends(me)
    return me


def leave_desk() -> None:
    """The batch has ended: this process's rings are unmapped (a spawned process's go as it exits)."""
    global _desks, _me, _standby
    if _standby is not None:
        _standby.close_receivers()
    if _desks is not None:
        for desk in _desks.desks:
            desk.drop_sender()
    _desks = _me = _standby = None


def standby_helpers() -> StandbyHelpers | None:
    """This process's desk, while it is one of a batch's processes (else None)."""
    if _desks is not None:
        _desks.keep_own_ends(_me)     # process 0: once the spawned ones hold theirs
    return _standby


def help_for_a_while() -> tuple[int, int]:
    """In a batch's spawned process with nothing left to take: help the others' renders for about
    HELP_SLICE_S (its feeder calls again until the batch ends); (this process, the frames it has rendered
    for them so far)."""
    return os.getpid(), _desks.help_for(_me, HELP_SLICE_S)
