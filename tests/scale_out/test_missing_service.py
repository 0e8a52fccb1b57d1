"""A scale-out service that is down (Postgres or Redis) gives one line naming it, where it was looked for
and the command that starts it; nothing waits on a driver's retries. Needs no server: the ports are free."""

from __future__ import annotations

import subprocess
import sys

import dagster as dg
import pytest

from b2d_pipeline.scale_out import REDIS, ServiceUnavailable, executor_named, require, write_postgres_instance_yaml
from b2d_pipeline.scale_out.instance_yaml import require_instance_services
from loopback_services import REPO, free_port


def _one_line(text: str) -> str:
    assert "\n" not in text.strip(), text
    return text.strip()


def test_redis_down_names_it_and_its_start_command():
    port = free_port()
    with pytest.raises(ServiceUnavailable) as caught:
        require(REDIS, f"redis://127.0.0.1:{port}/0", what="Celery broker")
    assert _one_line(str(caught.value)) == (f"Redis (Celery broker) is not reachable at 127.0.0.1:{port}: "
                                            f"connection refused; start it with `B2D_REDIS_PORT={port} deploy/redis.sh start`")
    assert REDIS.start_command(6379) == "deploy/redis.sh start"        # the default port needs no setting


def test_postgres_down_names_the_instance_file_and_its_start_command(tmp_path):
    port = free_port()
    path = write_postgres_instance_yaml(tmp_path, f"postgresql://b2d:secret@127.0.0.1:{port}/b2d")
    with pytest.raises(ServiceUnavailable) as caught:
        require_instance_services(tmp_path)
    message = _one_line(str(caught.value))
    assert message.startswith(f"Postgres (instance storage of {path}) is not reachable at 127.0.0.1:{port}")
    assert message.endswith(f"start it with `B2D_PG_PORT={port} deploy/postgres.sh start`")
    assert "secret" not in message


def test_postgres_url_variable_unset_names_the_file_and_variable(tmp_path, monkeypatch):
    monkeypatch.delenv("B2D_POSTGRES_URL", raising=False)
    path = write_postgres_instance_yaml(tmp_path)
    with pytest.raises(ValueError, match=f"{path}: storage.postgres.postgres_url reads the environment variable "
                                         "B2D_POSTGRES_URL, which is not set"):
        require_instance_services(tmp_path)


def test_celery_run_with_redis_down_fails_before_any_step(monkeypatch):
    pytest.importorskip("dagster_celery", reason="dagster-celery is not installed (pip install -e '.[scale]')")
    from b2d_pipeline.scale_out.probe import celery_probe_job

    port = free_port()
    monkeypatch.setenv("B2D_CELERY_BROKER", f"redis://127.0.0.1:{port}/0")
    with dg.instance_for_test() as instance:
        with pytest.raises(ServiceUnavailable, match=f"Redis \\(Celery broker\\) is not reachable at 127.0.0.1:{port}"):
            dg.execute_job(dg.reconstructable(celery_probe_job), instance, tags={"dagster/partition": "p0"})
        assert not instance.get_materialized_partitions(dg.AssetKey("probe_source"))


def test_worker_with_redis_down_exits_with_one_line(tmp_path):
    pytest.importorskip("dagster_celery", reason="dagster-celery is not installed (pip install -e '.[scale]')")
    port = free_port()
    env = {"PATH": "/usr/bin:/bin", "DAGSTER_HOME": str(tmp_path), "B2D_CELERY_BROKER": f"redis://127.0.0.1:{port}/0"}
    done = subprocess.run([sys.executable, "-m", "b2d_pipeline.scale_out.worker", "w1"], env=env, cwd=REPO,
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 1
    assert _one_line(done.stderr) == (f"b2d worker: Redis (Celery broker) is not reachable at 127.0.0.1:{port}: "
                                      f"connection refused; start it with `B2D_REDIS_PORT={port} deploy/redis.sh start`")


def test_unknown_executor_lists_the_valid_names():
    with pytest.raises(KeyError, match="unknown executor 'dask'; valid names: default, in_process, multiprocess, celery, k8s"):
        executor_named("dask")
    assert executor_named("default") is dg.multi_or_in_process_executor



# `b2d materialize` itself: the service that is down is the last line, no traceback, and nothing is produced

def _materialize(monkeypatch, tmp_path, **env):
    from click.testing import CliRunner

    from b2d_cli.main import cli

    monkeypatch.delenv("B2D_TRACEBACK", raising=False)
    for name, value in {"B2D_DATA_ROOT": str(tmp_path / "data"), "DAGSTER_HOME": str(tmp_path / "home"), **env}.items():
        monkeypatch.setenv(name, value)
    result = CliRunner().invoke(cli, ["materialize", "--max-steps", "4"])
    return result, result.output.strip().splitlines()[-1]


def test_materialize_on_celery_with_redis_down_says_so_in_one_line(tmp_path, monkeypatch):
    pytest.importorskip("dagster_celery", reason="dagster-celery is not installed (pip install -e '.[scale]')")
    port = free_port()
    result, last = _materialize(monkeypatch, tmp_path, B2D_EXECUTOR="celery", B2D_CELERY_BROKER=f"redis://127.0.0.1:{port}/0")
    assert result.exit_code == 1
    assert last == (f"error: ServiceUnavailable: Redis (Celery broker) is not reachable at 127.0.0.1:{port}: "
                    f"connection refused; start it with `B2D_REDIS_PORT={port} deploy/redis.sh start`")
    assert "Traceback" not in result.output
    assert not (tmp_path / "data" / "raw").exists()           # no step ran


def test_materialize_on_a_postgres_instance_that_is_down_says_so_in_one_line(tmp_path, monkeypatch):
    port = free_port()
    path = write_postgres_instance_yaml(tmp_path / "home")        # the URL from B2D_POSTGRES_URL
    result, last = _materialize(monkeypatch, tmp_path, B2D_POSTGRES_URL=f"postgresql://b2d:secret@127.0.0.1:{port}/b2d")
    assert result.exit_code == 1
    assert last == (f"error: ServiceUnavailable: Postgres (instance storage of {path}) is not reachable at "
                    f"127.0.0.1:{port}: connection refused; start it with `B2D_PG_PORT={port} deploy/postgres.sh start`")
    assert "secret" not in result.output and "Traceback" not in result.output
    assert not (tmp_path / "data").exists()

    monkeypatch.delenv("B2D_POSTGRES_URL")                         # the variable the file reads is not set
    result, last = _materialize(monkeypatch, tmp_path)
    assert result.exit_code == 2
    assert last.startswith(f"error: ValueError: {path}: storage.postgres.postgres_url reads the environment variable "
                           "B2D_POSTGRES_URL, which is not set")
