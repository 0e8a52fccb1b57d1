"""A batch's process with no recording left to take helps render another's (issue 22 item 3).

`b2d replay RAW... --workers N` replays whole recordings on N processes (episodes/replay_batch.py). Near a
batch's end the process that started first has nothing left to take while a spawned one still renders its
last recording: on a short batch that tail was most of the loss (6 recordings on two cores: 1.63x one
worker). So each spawned process gets a desk, where it posts every render it starts; the batch's own
process, once it has nothing left to take, takes frames of the posted render with the most frames left,
as a render helper does (episodes/render_pool.py). The render's own process still writes every frame in
order, so each episode stays byte-identical to a one-worker replay; a render nobody helps is rendered
alone, as before.
"""

from __future__ import annotations

import os
import pickle
import time

from episodes.render_pool import JOB, MAX_AHEAD, NEXT, STATE_SLOTS, TOTAL, WRITTEN, HelperChannels, _Sender, help_render

MIN_FRAMES_LEFT = 8      # fewer left: building a scene to help costs more than it saves
STALL_S = 30.0           # held back this long with no frame written: the render's process is stuck or gone


class Posted:
    """The latest render a spawned process started (job id, replay path, profile, steps), kept in shared
    memory: posting never blocks (a queue's pipe fills while the batch's process is busy with its own
    recordings) and only the latest one matters."""

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
        return pickle.loads(data) if data else None      # written by the spawned process, in memory


class Desk:
    """One spawned process's desk, made by the batch's process and handed to the spawned one as it starts:
    the shared counters of its renders, the render it last started, and a pipe for the frames rendered
    for it."""

    def __init__(self, ctx):
        self.lock, self.state = ctx.Lock(), ctx.RawArray("q", STATE_SLOTS)
        self.posted = Posted(ctx)
        self.reader, self.writer = ctx.Pipe(duplex=False)
        self.pid = ctx.RawValue("q", 0)       # the spawned process that took this desk
        self._task: tuple | None = None       # the batch process's side: the render posted, once read

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

    def help(self) -> int:
        """Render frames of the latest render posted until none is left; the number rendered."""
        out, written, since = _Sender(self.writer), -1, time.monotonic()

        def still_wanted() -> bool:      # asked while the render's process holds this one back
            nonlocal written, since
            if out.broken or not _alive(self.pid.value):
                return False
            if self.state[WRITTEN] != written:
                written, since = self.state[WRITTEN], time.monotonic()
            return time.monotonic() - since < STALL_S

        count = help_render(self._task, 0, out, self.lock, self.state, MAX_AHEAD, still_wanted)
        out.finish(wait=still_wanted())
        return count


class Desks:
    """The batch process's side of its spawned processes' desks."""

    def __init__(self, ctx, count: int):
        self.desks = [Desk(ctx) for _ in range(count)]
        self.claimed = ctx.RawValue("i", 0)
        self.claim_lock = ctx.Lock()
        self.frames_helped = 0

    def for_workers(self) -> tuple:
        """What `take_desk` in a spawned process needs (passed as it starts)."""
        return self.desks, self.claimed, self.claim_lock

    def help_one(self) -> bool:
        """Help the spawned processes' render with the most frames left, if one has enough left to be worth
        a scene; False when none has."""
        left, desk = max(((d.frames_left(), i) for i, d in enumerate(self.desks)), default=(0, 0))
        if left < MIN_FRAMES_LEFT:
            return False
        self.frames_helped += self.desks[desk].help()
        return True


class StandbyHelper(HelperChannels):
    """A spawned process's side of its desk: the batch's process as its one render helper, which joins a
    render only once it has nothing left of its own (until then the render runs alone, as before)."""

    def __init__(self, desk: Desk):
        desk.writer.close()      # this process only reads the frames
        super().__init__(1, MAX_AHEAD, desk.lock, desk.state, [desk.posted], [desk.reader])

    def _helper_alive(self, k: int) -> bool:
        return True     # the batch's process: this one ends with it (workers.die_with_parent)


_standby: StandbyHelper | None = None


def take_desk(desks: list[Desk], claimed, claim_lock) -> None:
    """In a batch's spawned process, as it starts: take the next free desk; its renders post there."""
    global _standby
    with claim_lock:
        desk = desks[claimed.value]
        claimed.value += 1
    desk.pid.value = os.getpid()
    _standby = StandbyHelper(desk)


def standby_helper() -> StandbyHelper | None:
    """This process's desk, if it is a batch's spawned process (else None)."""
    return _standby


def _alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
