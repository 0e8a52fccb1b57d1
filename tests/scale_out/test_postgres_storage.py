"""Dagster's run, event and schedule storage on Debian's PostgreSQL started by deploy/postgres.sh: a
partition materialised into that instance is read back by a second instance object (a new connection)
and is in the database's own tables."""

from __future__ import annotations

import os

import dagster as dg
import yaml

from b2d_pipeline.scale_out.instance_yaml import require_instance_services
from b2d_pipeline.scale_out.probe import PROBE_ASSETS


def test_materialization_on_postgres_reads_back(postgres, postgres_home):
    url, env, _ = postgres
    with dg.DagsterInstance.from_config(str(postgres_home)) as instance:
        assert type(instance.run_storage).__name__ == "PostgresRunStorage"
        assert type(instance.event_log_storage).__name__ == "PostgresEventLogStorage"
        assert type(instance.schedule_storage).__name__ == "PostgresScheduleStorage"
        result = dg.materialize(PROBE_ASSETS, instance=instance, partition_key="p1")
        assert result.success
        run_id = result.run_id

    require_instance_services(postgres_home)          # no error while the server is up
    with dg.DagsterInstance.from_config(str(postgres_home)) as again:
        run = again.get_run_by_id(run_id)
        assert run.status == dg.DagsterRunStatus.SUCCESS and run.tags["dagster/partition"] == "p1"
        materialized = {e.dagster_event.step_materialization_data.materialization.asset_key.path[-1]:
                        e.dagster_event.step_materialization_data.materialization
                        for e in again.all_logs(run_id) if e.is_dagster_event and e.dagster_event.is_step_materialization}
        assert set(materialized) == {"probe_source", "probe_left", "probe_right", "probe_join"}
        assert materialized["probe_join"].metadata["pid"].value == os.getpid()    # materialize() runs in process
        assert materialized["probe_join"].partition == "p1"
        assert "p1" in again.get_materialized_partitions(dg.AssetKey("probe_left"))

    import psycopg2    # the rows are in PostgreSQL itself, not in a file beside DAGSTER_HOME
    with psycopg2.connect(url.replace("+psycopg2", "")) as connection, connection.cursor() as cursor:
        cursor.execute("SELECT status FROM runs WHERE run_id = %s", (run_id,))
        assert cursor.fetchone() == ("SUCCESS",)
        cursor.execute("SELECT count(*) FROM event_logs WHERE run_id = %s AND dagster_event_type = "
                       "'ASSET_MATERIALIZATION'", (run_id,))
        assert cursor.fetchone() == (4,)
    assert not (postgres_home / "history").exists()   # SQLite's run storage folder


def test_instance_yaml_by_environment_variable_keeps_the_password_out(postgres, tmp_path, monkeypatch):
    from b2d_pipeline.scale_out import write_postgres_instance_yaml

    url = postgres[0]
    path = write_postgres_instance_yaml(tmp_path, None)
    text = path.read_text()
    assert url.split("@")[0].split(":")[-1] not in text                  # the password
    assert yaml.safe_load(text)["storage"] == {"postgres": {"postgres_url": {"env": "B2D_POSTGRES_URL"}}}
    assert oct(path.stat().st_mode & 0o777) == "0o600"
    monkeypatch.setenv("B2D_POSTGRES_URL", url)
    with dg.DagsterInstance.from_config(str(tmp_path)) as instance:
        assert type(instance.run_storage).__name__ == "PostgresRunStorage"
        assert instance.get_runs_count() >= 0

