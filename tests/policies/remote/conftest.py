"""One tiny ACT checkpoint for the remote-policy tests (two training steps on the session's episodes)."""

import pytest

from policies.config import load_policy_config
from policies.train import train_policy


@pytest.fixture(scope="session")
def remote_checkpoint(policy_episodes, tmp_path_factory):
    out = tmp_path_factory.mktemp("remote_ckpt") / "act"
    train_policy(load_policy_config("act", "tiny"), policy_episodes, out, steps=2)
    return out
