import copy

import pytest


@pytest.fixture(scope="session")
def tiny_episode(raw_path, tmp_path_factory):
    """The shared 18-step recording replayed into an episode: 3 frames (10 Hz), two 64x48 cameras,
    tactile on (ten 30x30 tacmaps)."""
    from episodes.stages import raw_to_episode
    from sim.registry import parse_sensor_profile, sensor_profile

    raw = copy.deepcopy(sensor_profile("preview").raw)
    raw.update(name="media_tiny")
    raw["cameras"].update(ids=["chest", "overhead"], width=64, height=48)
    return raw_to_episode(raw_path, parse_sensor_profile(raw), tmp_path_factory.mktemp("media_episode"))
