"""deploy/postgres.sh and deploy/redis.sh: start and stop can be repeated, status tells, and a machine
without the Debian packages gets a message naming the package to install."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from loopback_services import DEPLOY, NEEDS_REDIS, free_port, run_script


def test_postgres_start_and_stop_are_idempotent(postgres):
    _, env, _ = postgres
    again = run_script("postgres.sh", "start", env)
    assert again.returncode == 0 and "already running" in again.stderr
    status = run_script("postgres.sh", "status", env)
    assert status.returncode == 0 and f"127.0.0.1:{env['B2D_PG_PORT']}" in status.stdout
    assert run_script("postgres.sh", "url", env).stdout.startswith("postgresql+psycopg2://b2d:")


def test_redis_start_and_stop_are_idempotent(tmp_path):
    if shutil.which("redis-server") is None:
        pytest.skip(NEEDS_REDIS)
    env = {"B2D_SERVICES_DIR": str(tmp_path), "B2D_REDIS_PORT": str(free_port())}
    assert run_script("redis.sh", "start", env).returncode == 0
    again = run_script("redis.sh", "start", env)
    assert again.returncode == 0 and "already running" in again.stderr
    assert run_script("redis.sh", "status", env).returncode == 0
    assert run_script("redis.sh", "stop", env).returncode == 0
    assert run_script("redis.sh", "stop", env).returncode == 0
    stopped = run_script("redis.sh", "status", env)
    assert stopped.returncode == 1 and stopped.stdout.strip() == "redis: stopped"


def test_missing_packages_are_named(tmp_path):
    no_pg = subprocess.run([str(DEPLOY / "postgres.sh"), "start"], env={"PATH": "/usr/bin:/bin", "PG_BIN": "/nonexistent",
                           "B2D_SERVICES_DIR": str(tmp_path)}, capture_output=True, text=True)
    assert no_pg.returncode == 3
    assert no_pg.stderr.strip() == "postgres.sh: PostgreSQL's server is not installed (apt-get install postgresql)"
    empty = tmp_path / "bin"            # a PATH with the script's basic tools but no redis-server
    empty.mkdir()
    (empty / "dirname").symlink_to(shutil.which("dirname"))
    no_redis = subprocess.run(["/bin/bash", str(DEPLOY / "redis.sh"), "start"], env={"PATH": str(empty),
                              "B2D_SERVICES_DIR": str(tmp_path)}, capture_output=True, text=True)
    assert no_redis.returncode == 3
    assert no_redis.stderr.strip() == "redis.sh: redis-server is not installed (apt-get install redis-server)"
    assert not (tmp_path / "postgres").exists() and not (tmp_path / "redis").exists()
