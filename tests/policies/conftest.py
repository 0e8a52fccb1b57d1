"""Small real training data: two short scripted demonstrations of the foundation setting, replayed and
rendered under the `policy_tiny` profile (four 64x48 views, 20 Hz, TacMap at step 8)."""

import pytest

from sim.registry import sensor_profile

SETTING = "citrus_plate_loading__ur5_rh5dg2"
TASK, EMBODIMENT = SETTING.split("__")


@pytest.fixture(scope="session")
def policy_episodes(tmp_path_factory):
    from episodes.stages import raw_to_episode
    from teleop.demos import record_demonstrations

    raw = tmp_path_factory.mktemp("policy_raw")
    results = record_demonstrations(TASK, EMBODIMENT, 2, raw, max_steps=45)
    assert all(r.error is None for r in results), [r.error for r in results]
    out = tmp_path_factory.mktemp("policy_episodes")
    profile = sensor_profile("policy_tiny")
    return [raw_to_episode(r.path, profile, out) for r in results]


@pytest.fixture(autouse=True, scope="module")
def one_thread():
    """Tiny models gain nothing from more threads, and on a busy machine (or under xdist) OpenMP
    threads waiting for each other can stall single steps for seconds."""
    import torch

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)
