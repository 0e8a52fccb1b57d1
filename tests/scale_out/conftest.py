"""Real services on loopback for the scale-out tests: Debian's PostgreSQL and redis-server started by the
project's own scripts (deploy/*.sh) in a temporary folder on free ports, Celery workers as subprocesses.
Skipped, with the reason, where the Debian packages or the `scale` extra are not installed."""

from __future__ import annotations

import glob
import os
import shutil
import tempfile
import time
from pathlib import Path

import pytest

from loopback_services import CELERY_PROFILE, NEEDS_POSTGRES, NEEDS_REDIS, free_port, run_script


@pytest.fixture(scope="session")
def services_dir():
    # under /tmp, not pytest's 0700 folder: as root the server runs as user postgres, which must reach it
    path = Path(tempfile.mkdtemp(prefix="b2d-services-", dir="/tmp"))
    path.chmod(0o755)
    yield path
    shutil.rmtree(path, ignore_errors=True)


@pytest.fixture(scope="session")
def postgres(services_dir):
    """(url, env, seconds to start) of a PostgreSQL started by deploy/postgres.sh."""
    pytest.importorskip("dagster_postgres", reason="dagster-postgres is not installed (pip install -e '.[scale]')")
    if not glob.glob("/usr/lib/postgresql/*/bin/pg_ctl"):
        pytest.skip(NEEDS_POSTGRES)
    env = {"B2D_SERVICES_DIR": str(services_dir), "B2D_PG_PORT": str(free_port()),
           "B2D_PG_OPTIONS": "-c fsync=off -c synchronous_commit=off"}     # a throwaway cluster
    started = time.perf_counter()
    done = run_script("postgres.sh", "start", env)
    seconds = time.perf_counter() - started
    assert done.returncode == 0, done.stderr
    url = run_script("postgres.sh", "url", env).stdout.strip()
    yield url, env, seconds
    run_script("postgres.sh", "stop", env)


@pytest.fixture(scope="session")
def redis(services_dir):
    """(url, env) of a redis-server started by deploy/redis.sh."""
    pytest.importorskip("dagster_celery", reason="dagster-celery is not installed (pip install -e '.[scale]')")
    if shutil.which("redis-server") is None:
        pytest.skip(NEEDS_REDIS)
    env = {"B2D_SERVICES_DIR": str(services_dir), "B2D_REDIS_PORT": str(free_port())}
    done = run_script("redis.sh", "start", env)
    assert done.returncode == 0, done.stderr
    yield run_script("redis.sh", "url", env).stdout.strip(), env
    run_script("redis.sh", "stop", env)


@pytest.fixture()
def postgres_home(postgres, tmp_path):
    """A DAGSTER_HOME whose instance keeps runs, events and schedules in the test's PostgreSQL."""
    from b2d_pipeline.scale_out import write_postgres_instance_yaml

    home = tmp_path / "dagster_home"
    write_postgres_instance_yaml(home, postgres[0])
    return home


@pytest.fixture(scope="session")
def celery_run(postgres, redis, tmp_path_factory):
    """Two Celery workers (w1, w2: subprocesses, one step at a time each) on the test's Redis, for runs on an
    instance in the test's PostgreSQL, with the factory's settings in their environment (data root, a small
    sensor profile). Yields (names of the workers, DAGSTER_HOME, the environment a run needs)."""
    from b2d_pipeline.scale_out import write_postgres_instance_yaml
    from b2d_pipeline.scale_out.local_workers import LocalWorkers

    home = tmp_path_factory.mktemp("celery_home")
    write_postgres_instance_yaml(home, postgres[0])
    base = redis[0]
    run_env = {"B2D_CELERY_BROKER": f"{base}/0", "B2D_CELERY_BACKEND": f"{base}/1", "B2D_EXECUTOR": "celery",
               "B2D_DATA_ROOT": str(tmp_path_factory.mktemp("celery_data")), "B2D_PROFILE": CELERY_PROFILE}
    env = {**os.environ, **run_env, "DAGSTER_HOME": str(home), "MUJOCO_GL": os.environ.get("MUJOCO_GL") or "egl"}
    workers = LocalWorkers(["w1", "w2"], env, tmp_path_factory.mktemp("celery_logs"),
                           preload=("b2d_pipeline.scale_out.probe", "b2d_pipeline.chain"))
    try:
        yield workers.wait_ready(run_env["B2D_CELERY_BROKER"]), home, run_env
    finally:
        workers.stop()
