"""Issue 22 item 3: in a batch, the process with no recording left helps another process's render
(episodes/render_desk.py). Here this test's process plays the batch's spawned process (it renders and
writes) and a spawned process plays the batch's own, helping from its side of the desk. The render file
is the one-worker file whoever renders which frame, and a render nobody helps is rendered alone."""

import multiprocessing
import os
import signal

import pytest

from episodes import render_desk, stages
from episodes.atomic import file_sha256
from episodes.stages import render_to_file
from sim.registry import parse_sensor_profile
from held_frames import held_until_helpers_take
from tiny_profile import TINY as TINY_FIELDS

TINY = parse_sensor_profile(TINY_FIELDS)


def _help_once_idle(desks, go, helped) -> None:
    """The batch's process 0, once it has nothing left to take (`go`): help the others until the batch ends."""
    go.wait(60)
    while not desks.finished.value:
        desks.help_for(0, 1.0)
    helped.put(desks.frames_helped)


_WaitingForTheHelper = held_until_helpers_take(render_desk.standby_helpers)


@pytest.mark.timeout(180)     # a writer that waits for a helper forever fails here, not in CI's limit
def test_the_batch_process_helps_a_posted_render_and_the_file_is_the_one_worker_file(replay_path, tmp_path,
                                                                                      monkeypatch):
    one = render_to_file(replay_path, TINY, tmp_path / "one.render.h5")
    assert one["workers"] == 1 and one["frames"] >= 2 * render_desk.MIN_FRAMES_LEFT

    ctx = multiprocessing.get_context("spawn")
    desks = render_desk.Desks(ctx, 2)
    go, helped = ctx.Event(), ctx.Queue()
    batch = ctx.Process(target=_help_once_idle, args=(desks, go, helped), daemon=True)
    batch.start()
    assert render_desk.take_desk(desks) == 1      # this process: the batch's spawned one
    try:
        # the batch's process is busy: the render runs alone and does not wait for it
        alone = render_to_file(replay_path, TINY, tmp_path / "alone.render.h5")
        assert alone["workers"] == 1 and alone["helper_frames"] == 0
        go.set()
        monkeypatch.setattr(stages, "ReplayFrames", _WaitingForTheHelper)
        shared = render_to_file(replay_path, TINY, tmp_path / "shared.render.h5")
    finally:
        desks.finished.value = 1
        batch.join(timeout=60)
        render_desk.leave_desk()
    assert shared["workers"] == 2 and 0 < shared["helper_frames"] < shared["frames"]
    assert helped.get(timeout=60) == shared["helper_frames"]
    assert {file_sha256(tmp_path / f"{n}.render.h5") for n in ("alone", "shared")} == {
        file_sha256(tmp_path / "one.render.h5")}


class _KillingTheHelper(_WaitingForTheHelper):
    """The writer's own renderer, which kills the helping process once it has taken frames."""

    helper_pid = 0

    def capture(self, i):
        frame = super().capture(i)
        if self.helper_pid:
            os.kill(self.helper_pid, signal.SIGKILL)     # some of its frames may be sent, some lost
            _KillingTheHelper.helper_pid = 0
        return frame


@pytest.mark.timeout(180)     # the writer must see the killed helper's end, not wait for its frames
def test_a_helping_process_that_dies_mid_render_costs_time_not_bytes(replay_path, tmp_path, monkeypatch):
    one = render_to_file(replay_path, TINY, tmp_path / "one.render.h5")
    ctx = multiprocessing.get_context("spawn")
    desks = render_desk.Desks(ctx, 2)
    go, helped = ctx.Event(), ctx.Queue()
    batch = ctx.Process(target=_help_once_idle, args=(desks, go, helped), daemon=True)
    batch.start()
    render_desk.take_desk(desks)
    try:
        go.set()
        monkeypatch.setattr(_KillingTheHelper, "helper_pid", batch.pid)
        monkeypatch.setattr(stages, "ReplayFrames", _KillingTheHelper)
        info = render_to_file(replay_path, TINY, tmp_path / "killed.render.h5")
    finally:
        render_desk.leave_desk()
        batch.join(timeout=60)
    assert info["frames"] == one["frames"] and info["helper_frames"] == 0
    assert file_sha256(tmp_path / "killed.render.h5") == file_sha256(tmp_path / "one.render.h5")


def test_a_posted_render_is_the_latest_one_and_one_too_large_is_not_posted():
    posted = render_desk.Posted(multiprocessing.get_context("spawn"))
    assert posted.get() is None
    posted.put((1, "a.replay.h5", None, [0, 1]))
    posted.put((2, "b.replay.h5", None, [2, 3]))
    assert posted.get() == (2, "b.replay.h5", None, [2, 3])
    posted.put((3, "c.replay.h5", None, b"x" * render_desk.Posted.CAPACITY))
    assert posted.get() is None
