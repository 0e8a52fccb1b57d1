"""Two short real episodes under the `policy_tiny` profile (four 64x48 views, tactile 30x30, 20 Hz),
replayed from the session's recordings."""

import pytest

from sim.registry import sensor_profile


@pytest.fixture(scope="session")
def export_episodes(raw_dir, tmp_path_factory):
    from episodes.stages import raw_to_episode

    out = tmp_path_factory.mktemp("export_episodes")
    return [raw_to_episode(raw, sensor_profile("policy_tiny"), out) for raw in sorted(raw_dir.glob("*.raw.h5"))]
