"""Issue 22 item 3: render helpers kept across calls (episodes/render_pool.py). The writing process
renders beside them and writes every frame in order, so the render file's bytes are a one-worker
render's, whichever process rendered which frame, and also when a helper dies mid-render."""

import os
import signal
import time

import pytest

from episodes import render_pool, stages
from episodes.atomic import file_sha256
from episodes.render_pool import shared_helpers
from episodes.stages import frame_steps, render_to_file, replay_to_file
from sim.registry import parse_sensor_profile
from held_frames import held_until_helpers_take
from tiny_profile import TINY as TINY_FIELDS

TINY = parse_sensor_profile(TINY_FIELDS)


@pytest.fixture(scope="module")
def one_worker_sha(replay_path, tmp_path_factory):
    out = tmp_path_factory.mktemp("one") / "one.render.h5"
    assert render_to_file(replay_path, TINY, out)["workers"] == 1
    return file_sha256(out)


def test_a_render_does_not_wait_for_helpers_to_start(replay_path, one_worker_sha, tmp_path):
    # a fresh process's helpers need ~1.5 CPU-s to start (imports, GL); 18 tiny frames take far less, so
    # the writer renders them all alone instead of waiting, and the file is the same
    render_pool.close_shared_helpers()
    info = render_to_file(replay_path, TINY, tmp_path / "cold.render.h5", workers=2)
    pool = shared_helpers(1, wait=False)
    assert not pool.ready(0) and info["helper_frames"] == 0 and info["workers"] == 1
    assert file_sha256(tmp_path / "cold.render.h5") == one_worker_sha
    assert pool.wait_ready() and pool.ready(0)     # it went on starting, for the next render


_WaitingForHelpers = held_until_helpers_take(lambda: render_pool.shared_helpers(1))


def test_frames_from_helpers_give_the_one_worker_file_byte_for_byte(replay_path, one_worker_sha, tmp_path, monkeypatch):
    monkeypatch.setattr(stages, "ReplayFrames", _WaitingForHelpers)
    info = render_to_file(replay_path, TINY, tmp_path / "two.render.h5", workers=2)
    assert info["workers"] == 2 and 0 < info["helper_frames"] < info["frames"] == 18
    assert len(info["frame_windows"]) == 2 and info["helper_cpu_s"] > 0
    assert file_sha256(tmp_path / "two.render.h5") == one_worker_sha


def test_helpers_are_kept_across_calls_one_killed_mid_render_changes_no_byte_and_is_replaced(
        replay_path, one_worker_sha, tmp_path, monkeypatch):
    render_to_file(replay_path, TINY, tmp_path / "a.render.h5", workers=2)
    pool = shared_helpers(1)
    pid = pool._procs[0].pid
    render_to_file(replay_path, TINY, tmp_path / "b.render.h5", workers=2)
    assert shared_helpers(1) is pool and pool._procs[0].pid == pid      # the same warm process
    steps = frame_steps(18, TINY.rate_hz)
    with pool.job(replay_path, TINY, steps, helpers=1) as job:
        deadline = time.monotonic() + 60     # the helper takes frames until MAX_AHEAD holds it back
        while pool._state[render_pool.NEXT] < render_pool.MAX_AHEAD and time.monotonic() < deadline:
            time.sleep(0.01)
        os.kill(pid, signal.SIGKILL)      # some of its frames may be sent, some lost
        stats = stages._render_steps(replay_path, TINY, steps, tmp_path / "c.render.h5", job)
    assert stats["helper_frames"] == 0 and not pool.alive()
    render_to_file(replay_path, TINY, tmp_path / "d.render.h5", workers=2)     # starts a replacement
    assert shared_helpers(1) is not pool
    monkeypatch.setattr(stages, "ReplayFrames", _WaitingForHelpers)
    info = render_to_file(replay_path, TINY, tmp_path / "e.render.h5", workers=2)     # which takes part once up
    assert info["workers"] == 2
    assert {file_sha256(tmp_path / f"{n}.render.h5") for n in "abcde"} == {one_worker_sha}


def test_the_dagster_render_fan_out_with_two_render_workers_writes_the_one_worker_file(raw_path, one_worker_sha,
                                                                                        tmp_path):
    import dagster as dg

    from b2d_pipeline.definitions import build_definitions
    from b2d_pipeline.settings import FactorySettings
    from foundation_demos import SETTING

    settings = FactorySettings.from_env(data_root=tmp_path, profile=TINY, render_workers=2)
    replay_to_file(raw_path, tmp_path / "replays" / SETTING / "episode_0000.replay.h5")
    d = build_definitions(settings)
    with dg.DagsterInstance.ephemeral() as instance:
        result = dg.materialize(list(d.assets), selection=["renders"], partition_key=SETTING, instance=instance,
                                resources=d.resources)
    assert result.success
    rendered = tmp_path / "renders" / TINY.content_hash / SETTING / "episode_0000.render.h5"
    assert file_sha256(rendered) == one_worker_sha
