import os

os.environ.setdefault("MUJOCO_GL", "egl")

import pytest  # noqa: E402

from foundation_demos import EMBODIMENT, SETTING, TASK, record_foundation_demos  # noqa: E402,F401


@pytest.fixture(scope="session")
def raw_dir(tmp_path_factory):
    """Two short real recordings of the foundation setting (a few control steps each)."""
    out = tmp_path_factory.mktemp("raw")
    record_foundation_demos(out, 2, max_steps=18)
    return out


@pytest.fixture(scope="session")
def raw_path(raw_dir):
    return sorted(raw_dir.glob("*.raw.h5"))[0]
