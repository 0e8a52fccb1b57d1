"""A partition materialised through the celery executor on two Celery workers (subprocesses), with Redis
(deploy/redis.sh) as broker and result backend and the instance on PostgreSQL (deploy/postgres.sh): every
step runs in a worker's pool process, and the two branches of the probe graph run on the two workers."""

from __future__ import annotations

import os

import dagster as dg
import pytest

from b2d_pipeline.scale_out.local_workers import LocalWorkers
from b2d_pipeline.scale_out.probe import PROBE_ASSETS, celery_probe_job

pytest.importorskip("dagster_celery", reason="dagster-celery is not installed (pip install -e '.[scale]')")


@pytest.fixture()
def two_workers(postgres_home, redis, tmp_path, monkeypatch):
    base = redis[0]
    broker, backend = f"{base}/0", f"{base}/1"
    env = {**os.environ, "DAGSTER_HOME": str(postgres_home), "B2D_CELERY_BROKER": broker,
           "B2D_CELERY_BACKEND": backend}
    monkeypatch.setenv("B2D_CELERY_BROKER", broker)      # the run's own process submits the steps
    monkeypatch.setenv("B2D_CELERY_BACKEND", backend)
    workers = LocalWorkers(["w1", "w2"], env, tmp_path, preload=("b2d_pipeline.scale_out.probe",))
    try:
        yield workers.wait_ready(broker)
    finally:
        workers.stop()


def test_partition_runs_on_two_celery_workers(postgres_home, two_workers):
    assert [name.split("@")[0] for name in two_workers] == ["w1", "w2"]
    with dg.DagsterInstance.from_config(str(postgres_home)) as instance:
        result = dg.execute_job(dg.reconstructable(celery_probe_job), instance, tags={"dagster/partition": "p0"})
        assert result.success
        events = instance.all_logs(result.run_id)

    steps = {a.key.path[-1] for a in PROBE_ASSETS}
    # dagster-celery reports, per step, the worker that took it
    worker_of = {e.step_key: e.dagster_event.engine_event_data.metadata["Celery worker"].value
                 for e in events if e.is_dagster_event and e.dagster_event.is_engine_event
                 and "Celery worker" in (e.dagster_event.engine_event_data.metadata or {})}
    assert set(worker_of) == steps
    assert set(worker_of.values()) == set(two_workers)
    assert worker_of["probe_left"] != worker_of["probe_right"]          # the branches ran side by side
    pids = {e.step_key: e.dagster_event.step_materialization_data.materialization.metadata["pid"].value
            for e in events if e.is_dagster_event and e.dagster_event.is_step_materialization}
    assert set(pids) == steps and os.getpid() not in pids.values()      # not in the run's own process
    with dg.DagsterInstance.from_config(str(postgres_home)) as instance:
        assert instance.get_materialized_partitions(dg.AssetKey("probe_join")) >= {"p0"}
