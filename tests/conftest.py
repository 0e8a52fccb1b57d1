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


@pytest.fixture(scope="session")
def replay_path(raw_path, tmp_path_factory):
    """`raw_path` replayed (the physics state per control step), for the render tests; read only."""
    from episodes.stages import replay_to_file

    out = tmp_path_factory.mktemp("replay") / "e.replay.h5"
    replay_to_file(raw_path, out)
    return out


@pytest.fixture(autouse=True)
def _stop_signals_stay_default(request):
    """A library that leaves SIGTERM ignored in this worker process passes that on to every child a later
    test starts (an ignored disposition survives exec), and such a child outlives terminate(). Put it
    back after the test, and say which test it was."""
    yield
    if signal.getsignal(signal.SIGTERM) == signal.SIG_IGN:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        warnings.warn(f"{request.node.nodeid} left SIGTERM ignored; restored")


@pytest.fixture
def edited_task(tmp_path_factory, monkeypatch):
    """`edit(task, change)`: for this test the catalog serves a copy of the task's file, changed by
    `change(raw mapping)`, in place of its own (every registry lookup and `load_task` see only the copy).
    For states the catalog has no example of now, e.g. a draft plan or a task without one."""
    import yaml

    import sim.registry as registry
    from sim.tasks import load_task

    folder, real_files, copies = tmp_path_factory.mktemp("tasks"), registry._files, {}
    monkeypatch.setattr(registry, "_files", lambda kind: {**real_files(kind), **(copies if kind == "tasks" else {})})

    def edit(task: str, change) -> str:
        raw = yaml.safe_load(registry.catalog_path("tasks", task).read_text())
        change(raw)
        copies[task] = folder / f"{task}.yaml"
        copies[task].write_text(yaml.safe_dump(raw, sort_keys=False))
        load_task.cache_clear()
        return task

    yield edit
    load_task.cache_clear()
