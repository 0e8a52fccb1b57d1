"""Issue 23, item 6: an episode's bytes do not depend on the number of render workers.

(The other half of item 6, a renderer's images staying right whatever renderers were built and dropped
before it, is tests/test_render_speed_paths.py::test_renderer_dropped_without_close_leaves_others_intact.)"""

from episodes import stages
from episodes.atomic import file_sha256
from episodes.render_pool import shared_helpers
from episodes.stages import assemble_episode, render_to_file, replay_to_file
from held_frames import held_until_helpers_take


def test_one_and_two_workers_write_the_same_bytes(raw_path, tiny_profile, tmp_path, monkeypatch):
    replay = tmp_path / "episode_0000.replay.h5"
    replay_to_file(raw_path, replay)
    episodes = []
    shared_helpers(1)       # up before the render: one that is still starting is not waited for, takes no frame
    for name, workers in (("one", 1), ("two", 2)):
        if workers == 2:     # the writer waits for the helper's first frames (they render faster than its scene is built)
            monkeypatch.setattr(stages, "ReplayFrames", held_until_helpers_take(lambda: shared_helpers(1)))
        render = tmp_path / f"{name}.render.h5"
        assert render_to_file(replay, tiny_profile, render, workers=workers)["workers"] == workers
        episodes.append(tmp_path / name / "episode_0000.hdf5")
        assemble_episode(replay, render, tiny_profile, episodes[-1])
    # before: HDF5 recorded creation times in the joined render's groups (so two runs differed too), and
    # the render's writing history reached the episode's group layout
    assert file_sha256(episodes[0]) == file_sha256(episodes[1])
