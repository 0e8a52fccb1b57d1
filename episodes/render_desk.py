"""A batch's process with no recording left to take helps render the others' (issue 22 item 3).

`b2d replay RAW... --workers N` replays whole recordings on N processes (episodes/replay_batch.py). Near a
batch's end a process with nothing left to take used to wait while another still rendered its last
recording: on a short batch that tail was most of the loss (6 recordings on two cores: 1.63x one worker).
So every process of a batch has a desk where it posts each render it starts, and a process with nothing
left to take helps the posted render with the most frames left, as a render helper does
(episodes/render_pool.py). The render's own process still writes every frame in order, so each episode
stays byte-identical to a one-worker replay; a render nobody helps is rendered alone, as before.

Processes are numbered 0 (the batch's own) to N-1; on a desk, the helper slots are the other processes'.
"""

from __future__ import annotations

import os
import pickle
import time

from episodes.frame_messages import FrameSender
from episodes.render_pool import JOB, MAX_AHEAD, NEXT, STATE_SLOTS, TOTAL, WRITTEN, HelperChannels, help_render

MIN_FRAMES_LEFT = 8      # fewer left: building a scene to help costs more than it saves
STALL_S = 30.0           # held back this long with no frame written: the render's process is stuck or gone
HELP_POLL_S = 0.02       # a process with nothing left looks for a render to help this often


class Posted:
    """The latest render a process started (job id, replay path, profile, steps), kept in shared memory:
    posting never blocks (a queue's pipe fills while the others are busy with their own recordings) and
    only the latest one matters."""

    CAPACITY = 1 << 16      # bytes; a render that does not fit is not posted (it renders alone)

    def __init__(self, ctx):
        self._bytes, self._length, self._lock = ctx.RawArray("B", self.CAPACITY), ctx.RawValue("q", 0), ctx.Lock()

    def put(self, task: tuple) -> None:
        data = pickle.dumps(task, pickle.HIGHEST_PROTOCOL)
        with self._lock:
            if len(data) > self.CAPACITY:
                self._length.value = 0
                return
            self._bytes[:len(data)] = data
            self._length.value = len(data)

    def get(self) -> tuple | None:
        with self._lock:
            data = bytes(self._bytes[:self._length.value])
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
        self._task: tuple | None = None                # a helper's side: the render posted, once read

    def frames_left(self) -> int:
        """Frames of the render under way that no process has taken yet (0 when none is under way)."""
        with self.lock:
            job, left = self.state[JOB], int(self.state[TOTAL] - self.state[NEXT])
        if not job:
            return 0
        if self._task is None or self._task[0] != job:
            self._task = self.posted.get()     # posted just after the counters were set: maybe not yet
            if self._task is None or self._task[0] != job:
                return 0
        return left

    def help(self, slot: int) -> int:
        """Render frames of the render under way, as helper `slot`, until none is left; the number rendered."""
        self.helper_pids[slot] = os.getpid()
        out, written, since = FrameSender(self.writers[slot]), -1, time.monotonic()

        def still_wanted() -> bool:      # asked while the render's process holds this one back
            nonlocal written, since
            if out.broken or not _alive(self.owner.value):
                return False
            if self.state[WRITTEN] != written:
                written, since = self.state[WRITTEN], time.monotonic()
            return time.monotonic() - since < STALL_S

        count = help_render(self._task, slot, out, self.lock, self.state, MAX_AHEAD, still_wanted)
        out.finish(wait=still_wanted())
        return count


class Desks:
    """The desks of a batch's `processes` processes, made by process 0 and handed to the others as they
    start."""

    def __init__(self, ctx, processes: int):
        self.desks = [Desk(ctx, processes - 1) for _ in range(processes)]
        self.claimed, self.claim_lock = ctx.RawValue("i", 1), ctx.Lock()
        self.finished = ctx.RawValue("b", 0)      # the batch has ended: helping processes stop
        self.frames_helped = 0                    # by this process

    def help_one(self, me: int) -> bool:
        """Help the others' render with the most frames left, if one has enough left to be worth a scene;
        False when none has."""
        left, d = max(((desk.frames_left(), d) for d, desk in enumerate(self.desks) if d != me), default=(0, 0))
        if left < MIN_FRAMES_LEFT:
            return False
        self.frames_helped += self.desks[d].help(me if me < d else me - 1)
        return True

    def help_until_finished(self, me: int) -> int:
        """Help the others' renders until the batch has ended; the frames rendered for them."""
        while not self.finished.value:
            if not self.help_one(me):
                time.sleep(HELP_POLL_S)
        return self.frames_helped


class StandbyHelpers(HelperChannels):
    """A process's side of its own desk: the batch's other processes as its render helpers, each joining a
    render only once it has nothing left of its own (until then the render runs alone, as before)."""

    def __init__(self, desk: Desk):
        desk.owner.value = os.getpid()
        slots = len(desk.readers)
        super().__init__(slots, MAX_AHEAD, desk.lock, desk.state, [desk.posted] * slots, desk.readers)
        self.desk = desk

    def _helper_alive(self, k: int) -> bool:
        pid = self.desk.helper_pids[k]
        return pid == 0 or _alive(pid)      # one that never helped has no frame of ours


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
    return me


def leave_desk() -> None:
    global _desks, _me, _standby
    _desks = _me = _standby = None


def standby_helpers() -> StandbyHelpers | None:
    """This process's desk, while it is one of a batch's processes (else None)."""
    return _standby


def help_until_finished() -> int:
    """In a batch's spawned process with nothing left to take: help the others' renders until the batch
    ends; the frames rendered for them."""
    return _desks.help_until_finished(_me)


def _alive(pid: int) -> bool:
    """Whether process `pid` runs: a child that died stays as a zombie until its parent reaps it."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            return f.read().rsplit(b")", 1)[1].split()[0] != b"Z"
    except (OSError, IndexError):        # no /proc (not Linux): taken as running
        return True

