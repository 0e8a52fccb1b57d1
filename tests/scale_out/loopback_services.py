"""Helpers for the scale-out tests (a module of its own: `conftest` is a name every test folder uses)."""

from __future__ import annotations

import os
import socket
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
DEPLOY = REPO / "deploy"
NEEDS_POSTGRES = "Debian's PostgreSQL is not installed (apt-get install postgresql)"
NEEDS_REDIS = "Debian's redis-server is not installed (apt-get install redis-server)"
CELERY_PROFILE = "policy_tiny"      # the smallest catalog profile: Celery workers rebuild it by name


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def run_script(script: str, action: str, env: dict[str, str]) -> subprocess.CompletedProcess:
    return subprocess.run([str(DEPLOY / script), action], env={**os.environ, **env}, capture_output=True,
                          text=True, timeout=120)


def celery_worker_of_steps(events) -> dict[str, str]:
    """{step key: the Celery worker (NAME@host) that ran it}, from dagster-celery's engine event per step."""
    return {e.step_key: e.dagster_event.engine_event_data.metadata["Celery worker"].value
            for e in events if e.is_dagster_event and e.dagster_event.is_engine_event
            and "Celery worker" in (e.dagster_event.engine_event_data.metadata or {})}
