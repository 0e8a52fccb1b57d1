"""A tiny real episode (18 frames, two 32x24 cameras, coarse tactile) with its manifest, made once."""

import shutil

import pytest

from sim.registry import parse_sensor_profile
from tiny_profile import TINY


@pytest.fixture(scope="session")
def tiny_profile():
    return parse_sensor_profile(TINY)


@pytest.fixture(scope="session")
def episode_dir(raw_path, tiny_profile, tmp_path_factory):
    from episodes.manifest import write_manifest
    from episodes.stages import raw_to_episode

    out = tmp_path_factory.mktemp("reliability_episode")
    path = raw_to_episode(raw_path, tiny_profile, out)
    write_manifest(out, updated=[path])
    shutil.rmtree(out / ".work")
    return out


@pytest.fixture
def episode_copy(episode_dir, tmp_path):
    """A copy of the episode folder (episode + manifest) that a test may damage."""
    out = tmp_path / "episodes"
    shutil.copytree(episode_dir, out)
    return out / "episode_0000.hdf5"


@pytest.fixture(scope="session")
def recorded_stream(tmp_path_factory):
    """A small recorded operator stream (teleop/streams/recorded.py): four frames, both wrists."""
    import numpy as np

    from teleop.streams.frame import OperatorFrame
    from teleop.streams.recorded import write_stream

    frames = []
    for k in range(4):
        frame = OperatorFrame.empty(1_000_000 * k)
        for side in ("left", "right"):
            frame = frame.with_hand(side, wrist_pos=np.array([0.1 * k, 0.0, 0.2]), wrist_quat=np.array([1.0, 0, 0, 0]))
        frames.append(frame)
    return write_stream(tmp_path_factory.mktemp("stream") / "stream.npz", frames)
