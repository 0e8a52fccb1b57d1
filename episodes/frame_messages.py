"""Messages between render processes, one pipe message per frame (episodes/render_pool.py).

A frame's arrays travel beside its pickle (protocol 5 out-of-band buffers), copied once into one block
with it, each array aligned as numpy allocates; the receiver reads the block into one writable buffer
and the arrays are views of it. Pickles cross only this pipe, in memory, between processes of one run
(as `concurrent.futures` passes its work); nothing is read back from disk this way.
"""

from __future__ import annotations

import pickle
import queue
import threading

import numpy as np


class FrameSender:
    """Messages to the writer through this helper's own pipe, written by a thread so that rendering
    goes on while the writer is busy. A pipe per helper: if a helper dies mid-message, the writer
    reads end-of-file instead of waiting for the rest forever (as on a queue every helper writes to).

    Arrays travel beside the pickle (protocol 5 out-of-band buffers): a paper frame is ~24 MB, and
    pickling it whole cost ~17 ms each side where a copy costs ~3. They are copied here, at once,
    as the next capture may reuse its buffers, into one block with the pickle: a preview frame has
    ~95 arrays, and a pipe message each cost the two processes ~0.9 ms a frame together."""

    def __init__(self, conn):
        self._conn, self._queue = conn, queue.SimpleQueue()
        self.broken = False         # the writer's end closed: nothing sent from here on arrives
        self._thread = threading.Thread(target=self._run, name="render-helper-sender", daemon=True)
        self._thread.start()

    def send(self, *message) -> None:
        buffers: list[pickle.PickleBuffer] = []
        head = pickle.dumps(message, 5, buffer_callback=buffers.append)
        self._queue.put(_pack(head, [b.raw() for b in buffers]))

    def _run(self) -> None:
        while (parts := self._queue.get()) is not None:
            sizes, block = parts
            try:
                self._conn.send_bytes(sizes)
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


ALIGN = 64      # each array's bytes start at a multiple of this in a message's block (as numpy allocates)


def _offsets(sizes: np.ndarray) -> np.ndarray:
    """Where each part starts in a block holding them in order, every part aligned to ALIGN."""
    padded = -(-sizes // ALIGN) * ALIGN
    return np.concatenate([[0], np.cumsum(padded)[:-1]]).astype(np.int64)


def _pack(head: bytes, arrays: list[memoryview]) -> tuple[bytes, bytearray]:
    """A message as (its parts' sizes, one block of the pickle and the arrays' bytes, each aligned)."""
    sizes = np.array([len(head), *(a.nbytes for a in arrays)], np.int64)
    offsets = _offsets(sizes)
    block = bytearray(int(offsets[-1] + sizes[-1]))
    for part, start, size in zip([head, *arrays], offsets, sizes):
        block[start:start + size] = part
    return sizes.tobytes(), block


def receive_message(reader):
    """One message of a `FrameSender`: its parts' sizes, then one block of its pickle and its arrays' bytes,
    read into one buffer (writable; each array aligned within it, as the arrays it becomes)."""
    sizes = np.frombuffer(reader.recv_bytes(), np.int64)
    offsets = _offsets(sizes)
    block = bytearray(int(offsets[-1] + sizes[-1]))
    reader.recv_bytes_into(block)
    view = memoryview(block)
    head, *buffers = (view[start:start + size] for start, size in zip(offsets, sizes))
    return pickle.loads(head, buffers=buffers)
