"""A writing process's renderer held back until its helpers have taken frames, for the render tests: tiny
frames render faster than a helper builds its scene, and a test must see helper-made frames written."""

import time

from episodes.render_pool import NEXT
from episodes.replay_frames import ReplayFrames


def held_until_helpers_take(channels) -> type[ReplayFrames]:
    """A ReplayFrames whose captures wait (up to 60 s) until the helpers of `channels()` (the writer's side
    of its helpers) have taken frames 0-2 between them."""

    class Held(ReplayFrames):
        def capture(self, i):
            deadline = time.monotonic() + 60
            while channels()._state[NEXT] < 3 and time.monotonic() < deadline:
                time.sleep(0.01)
            return super().capture(i)

    return Held
