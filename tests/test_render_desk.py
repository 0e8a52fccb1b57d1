"""Issue 22 item 3: in a batch, the process with no recording left helps another process's render
(episodes/render_desk.py). Here this test's process plays the batch's spawned process (it renders and
writes) and a spawned process plays the batch's own, helping from its side of the desk. The render file
is the one-worker file whoever renders which frame, and a render nobody helps is rendered alone."""

import multiprocessing
import time

import pytest

from episodes import render_desk, stages
from episodes.atomic import file_sha256
from episodes.render_pool import NEXT
from episodes.replay_frames import ReplayFrames
from episodes.stages import render_to_file, replay_to_file
from sim.registry import parse_sensor_profile
from tiny_profile import TINY as TINY_FIELDS

TINY = parse_sensor_profile(TINY_FIELDS)


@pytest.fixture(scope="module")
def replay(raw_path, tmp_path_factory):
    out = tmp_path_factory.mktemp("desk") / "e.replay.h5"
    replay_to_file(raw_path, out)
    return out


def _help_until_stopped(desks, go, stop, helped) -> None:
    """The batch's own process, once it has nothing left to take (`go`): help whatever render is posted."""
    go.wait(60)
    while not stop.is_set():
        if not desks.help_one():
            time.sleep(0.01)
    helped.put(desks.frames_helped)


class _WaitingForTheHelper(ReplayFrames):
    """The writer's own renderer, held at its first frame until the helper has taken frames: tiny frames
    render faster than the helper builds its scene, and the test must see its frames written."""

    def capture(self, i):
        deadline = time.monotonic() + 60
        while render_desk.standby_helper()._state[NEXT] < 3 and time.monotonic() < deadline:
            time.sleep(0.01)
        return super().capture(i)


def test_the_batch_process_helps_a_posted_render_and_the_file_is_the_one_worker_file(replay, tmp_path,
                                                                                      monkeypatch):
    one = render_to_file(replay, TINY, tmp_path / "one.render.h5")
    assert one["workers"] == 1 and one["frames"] >= 2 * render_desk.MIN_FRAMES_LEFT

    ctx = multiprocessing.get_context("spawn")
    desks = render_desk.Desks(ctx, 1)
    go, stop, helped = ctx.Event(), ctx.Event(), ctx.SimpleQueue()
    batch = ctx.Process(target=_help_until_stopped, args=(desks, go, stop, helped), daemon=True)
    batch.start()
    monkeypatch.setattr(render_desk, "_standby", None)
    render_desk.take_desk(*desks.for_workers())      # this process: the batch's spawned one
    try:
        # the batch's process is busy: the render runs alone and does not wait for it
        alone = render_to_file(replay, TINY, tmp_path / "alone.render.h5")
        assert alone["workers"] == 1 and alone["helper_frames"] == 0
        go.set()
        monkeypatch.setattr(stages, "ReplayFrames", _WaitingForTheHelper)
        shared = render_to_file(replay, TINY, tmp_path / "shared.render.h5")
    finally:
        stop.set()
        batch.join(timeout=60)
    assert shared["workers"] == 2 and 0 < shared["helper_frames"] < shared["frames"]
    assert helped.get() == shared["helper_frames"]
    assert {file_sha256(tmp_path / f"{n}.render.h5") for n in ("alone", "shared")} == {
        file_sha256(tmp_path / "one.render.h5")}


def test_a_posted_render_is_the_latest_one_and_one_too_large_is_not_posted():
    posted = render_desk.Posted(multiprocessing.get_context("spawn"))
    assert posted.get() is None
    posted.put((1, "a.replay.h5", None, [0, 1]))
    posted.put((2, "b.replay.h5", None, [2, 3]))
    assert posted.get() == (2, "b.replay.h5", None, [2, 3])
    posted.put((3, "c.replay.h5", None, b"x" * render_desk.Posted.CAPACITY))
    assert posted.get() is None
