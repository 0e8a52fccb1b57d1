import os

os.environ.setdefault("MUJOCO_GL", "egl")

import pytest  # noqa: E402

SETTING = "citrus_plate_loading__ur5_rh5dg2"
TASK, EMBODIMENT = SETTING.split("__")


@pytest.fixture(scope="session")
def raw_dir(tmp_path_factory):
    """Two short real recordings of the foundation setting (a few control steps each)."""
    from teleop.demos import record_demonstrations

    out = tmp_path_factory.mktemp("raw")
    results = record_demonstrations(TASK, EMBODIMENT, 2, out, max_steps=18)
    assert all(r.error is None for r in results), [r.error for r in results]
    return out


@pytest.fixture(scope="session")
def raw_path(raw_dir):
    return sorted(raw_dir.glob("*.raw.h5"))[0]
