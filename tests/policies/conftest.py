"""Small real training data: two short scripted demonstrations of the foundation setting, replayed and
rendered under the `policy_tiny` profile (four 64x48 views, 20 Hz, TacMap at step 8)."""

import pytest
from foundation_demos import record_foundation_demos

from sim.registry import sensor_profile


@pytest.fixture(scope="session")
def policy_episodes(tmp_path_factory):
    from episodes.stages import raw_to_episode

    raws = record_foundation_demos(tmp_path_factory.mktemp("policy_raw"), 2, max_steps=45)
    out = tmp_path_factory.mktemp("policy_episodes")
    return [raw_to_episode(raw, sensor_profile("policy_tiny"), out) for raw in raws]


@pytest.fixture(autouse=True, scope="module")
def one_thread():
    """Tiny models gain nothing from more threads, and on a busy machine (or under xdist) OpenMP
    threads waiting for each other can stall single steps for seconds."""
    import torch

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)
