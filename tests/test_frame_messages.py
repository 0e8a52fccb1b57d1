"""Frame messages between render processes: blocks through a shared-memory ring or the pipe arrive
the same, in the order sent; a ring is removed from /dev/shm once its receiver has it."""

import multiprocessing
import os
import time

import numpy as np
import pytest

from episodes import frame_messages
from episodes.frame_messages import RING_PREFIX, SHM_DIR, FrameReceiver, FrameSender, remove_stale_rings

SMALL, BIG = 70_000, 400_000     # bytes of a frame: a ring made for small ones has no room for a big one


def _frame(i: int, big: bool) -> dict:
    return {"rgb": np.full((BIG if big else SMALL,), i % 251, np.uint8), "pose": np.arange(i, i + 5.0),
            "odd": np.arange(12.0)[::2]}      # not contiguous: pickled in-band


def _send(conn, count: int, big_at: int, use_ring: bool) -> None:
    out = FrameSender(conn, use_ring=use_ring)
    for i in range(count):
        out.send("frame", 0, 1, i, _frame(i, i == big_at))
    out.send("done", 0, 1, None, {"ring": out.ring_blocks, "pipe": out.pipe_blocks})
    out.close()


def _exchange(use_ring: bool, pause_at: int = -1) -> tuple[list, dict]:
    ctx = multiprocessing.get_context("spawn")
    reader, writer = ctx.Pipe(duplex=False)
    sender = ctx.Process(target=_send, args=(writer, 60, 30, use_ring))
    sender.start()
    writer.close()
    receiver, frames = FrameReceiver(reader), []
    try:
        while (message := receiver.receive())[0] == "frame":
            if len(frames) == pause_at:
                time.sleep(0.2)     # the reader lags: the ring fills and blocks take the pipe
            frames.append(message)
    finally:
        sender.join(timeout=30)
        receiver.close()
        reader.close()
    return frames, message[4]


def _ours() -> list[str]:
    return sorted(f for f in os.listdir(SHM_DIR) if f.startswith(RING_PREFIX)) if SHM_DIR.is_dir() else []


@pytest.mark.skipif(not SHM_DIR.is_dir(), reason="no /dev/shm: every block goes through the pipe")
def test_blocks_through_the_ring_or_the_pipe_arrive_the_same_in_order_and_leave_no_file():
    before = _ours()
    through_ring, counts = _exchange(use_ring=True, pause_at=40)
    through_pipe, pipe_only = _exchange(use_ring=False)
    # through the ring, whose space the reader gives back as it reads (a bigger ring replaces it once all
    # is read); through the pipe, what found it full while the reader paused
    assert counts["ring"] >= 40 and counts["ring"] + counts["pipe"] == 60
    assert pipe_only == {"ring": 0, "pipe": 60}
    assert [m[3] for m in through_ring] == list(range(60))
    for (_, _, _, i, a), (_, _, _, _, b) in zip(through_ring, through_pipe):
        assert a.keys() == b.keys()
        for key in a:
            assert a[key].dtype == b[key].dtype and np.array_equal(a[key], b[key]), (i, key)
        assert a["rgb"].size == (BIG if i == 30 else SMALL) and (a["rgb"] == i % 251).all()
        a["rgb"][0] = 0     # writable, as a block read from the pipe
    assert _ours() == before


@pytest.mark.skipif(not SHM_DIR.is_dir(), reason="no /dev/shm")
def test_blocks_that_find_the_ring_full_go_through_the_pipe_in_their_turn():
    before = _ours()
    reader, writer = multiprocessing.Pipe(duplex=False)
    sender, receiver = FrameSender(writer), FrameReceiver(reader)
    for i in range(10):             # nobody reads yet: the ring takes the first RING_FRAMES
        sender.send("frame", 0, 1, i, _frame(i, False))
    assert (sender.ring_blocks, sender.pipe_blocks) == (frame_messages.RING_FRAMES, 10 - frame_messages.RING_FRAMES)
    for i in range(10):
        _, _, _, j, frame = receiver.receive()
        assert j == i and (frame["rgb"] == i).all() and frame["pose"][0] == i
    sender.send("frame", 0, 1, 10, _frame(10, False))      # the ring read: room again
    assert receiver.receive()[3] == 10 and sender.ring_blocks == frame_messages.RING_FRAMES + 1
    sender.close()
    receiver.close()
    assert _ours() == before


@pytest.mark.skipif(not SHM_DIR.is_dir(), reason="no /dev/shm")
def test_a_ring_that_cannot_be_allocated_sends_through_the_pipe(monkeypatch):
    before = _ours()
    monkeypatch.setattr(frame_messages, "RING_FRAMES", 1 << 40)       # a ring far larger than /dev/shm
    monkeypatch.setattr(frame_messages, "RING_MAX_BYTES", 1 << 62)
    read, write = os.pipe()
    os.close(read)
    sender = FrameSender(multiprocessing.connection.Connection(write, readable=False))
    sender.send("frame", 0, 1, 0, _frame(0, False))
    sender.close()      # its thread found the pipe closed: nothing to read it
    assert (sender.ring_blocks, sender.pipe_blocks) == (0, 1) and _ours() == before


@pytest.mark.skipif(not SHM_DIR.is_dir(), reason="no /dev/shm")
def test_stale_rings_of_dead_processes_are_removed_and_live_ones_kept():
    child = multiprocessing.get_context("spawn").Process(target=time.sleep, args=(0,))
    child.start()
    child.join()
    dead = SHM_DIR / f"{RING_PREFIX}{child.pid}-1"
    live = SHM_DIR / f"{RING_PREFIX}{os.getpid()}-1"
    try:
        dead.write_bytes(b"x")
        live.write_bytes(b"x")
        remove_stale_rings()
        assert not dead.exists() and live.exists()
    finally:
        dead.unlink(missing_ok=True)
        live.unlink(missing_ok=True)


@pytest.mark.skipif(not SHM_DIR.is_dir(), reason="no /dev/shm")
def test_a_ring_the_receiver_cannot_open_is_an_os_error_and_both_ends_still_close():
    """As a helper's death is: the writer marks the helper lost and renders its frames itself."""
    reader, writer = multiprocessing.Pipe(duplex=False)
    sender, receiver = FrameSender(writer), FrameReceiver(reader)
    sender.send("frame", 0, 1, 0, _frame(0, False))
    sender.finish()     # all sent: the announcement and the block
    for ring in set(_ours()):
        if ring.startswith(f"{RING_PREFIX}{os.getpid()}-"):
            (SHM_DIR / ring).unlink()       # gone before the receiver reads its announcement
    with pytest.raises(OSError):
        receiver.receive()
    for _ in range(2):
        receiver.close()
        sender.close()


@pytest.mark.skipif(not SHM_DIR.is_dir() or os.getuid() != 0, reason="needs /dev/shm and a file of another user")
def test_another_users_ring_is_left_alone():
    child = multiprocessing.get_context("spawn").Process(target=time.sleep, args=(0,))
    child.start()
    child.join()
    theirs = SHM_DIR / f"{RING_PREFIX}{child.pid}-2"
    try:
        theirs.write_bytes(b"x")
        os.chown(theirs, 65534, 65534)
        remove_stale_rings()
        assert theirs.exists()
    finally:
        theirs.unlink(missing_ok=True)
