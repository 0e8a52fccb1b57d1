import os
import signal
import warnings

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


@pytest.fixture(autouse=True)
def _stop_signals_stay_default(request):
    """A library that leaves SIGTERM ignored in this worker process passes that on to every child a later
    test starts (an ignored disposition survives exec), and such a child outlives terminate(). Put it
    back after the test, and say which test it was."""
    yield
    if signal.getsignal(signal.SIGTERM) == signal.SIG_IGN:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        warnings.warn(f"{request.node.nodeid} left SIGTERM ignored; restored")
