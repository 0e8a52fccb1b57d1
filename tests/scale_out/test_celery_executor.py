"""A partition materialised through the celery executor on two Celery workers (subprocesses), with Redis
(deploy/redis.sh) as broker and result backend and the instance on PostgreSQL (deploy/postgres.sh): every
step runs in a worker's pool process, and the two branches of the probe graph run on the two workers."""

from __future__ import annotations

import os

import dagster as dg
import pytest

from b2d_pipeline.scale_out.probe import PROBE_ASSETS, celery_probe_job
from loopback_services import celery_worker_of_steps

pytest.importorskip("dagster_celery", reason="dagster-celery is not installed (pip install -e '.[scale]')")


def test_partition_runs_on_two_celery_workers(celery_run, monkeypatch):
    workers, home, run_env = celery_run
    for name, value in run_env.items():       # the run's own process submits the steps
        monkeypatch.setenv(name, value)
    assert [name.split("@")[0] for name in workers] == ["w1", "w2"]
    with dg.DagsterInstance.from_config(str(home)) as instance:
        result = dg.execute_job(dg.reconstructable(celery_probe_job), instance, tags={"dagster/partition": "p0"})
        assert result.success
        events = instance.all_logs(result.run_id)

    steps = {a.key.path[-1] for a in PROBE_ASSETS}
    worker_of = celery_worker_of_steps(events)   # dagster-celery reports, per step, the worker that took it
    assert set(worker_of) == steps
    assert set(worker_of.values()) == set(workers)
    assert worker_of["probe_left"] != worker_of["probe_right"]          # the branches ran side by side
    pids = {e.step_key: e.dagster_event.step_materialization_data.materialization.metadata["pid"].value
            for e in events if e.is_dagster_event and e.dagster_event.is_step_materialization}
    assert set(pids) == steps and os.getpid() not in pids.values()      # not in the run's own process
    with dg.DagsterInstance.from_config(str(home)) as instance:
        assert instance.get_materialized_partitions(dg.AssetKey("probe_join")) >= {"p0"}
