"""A Dagster instance on PostgreSQL: runs, event logs and schedules in one database (dagster-postgres), so
that a webserver, a daemon and Celery workers on any host share one history, which SQLite cannot do (it
says "database is locked" under concurrent runs). Compute logs and artefacts stay in DAGSTER_HOME."""

from __future__ import annotations

import os
from pathlib import Path

import yaml

from b2d_pipeline.instance import instance_config
from b2d_pipeline.scale_out.services import POSTGRES, POSTGRES_URL_ENV, require
from episodes.atomic import atomic_path


def postgres_instance_config(postgres_url: str | None = None, cores: int | None = None) -> dict:
    """The project's instance settings with storage on Postgres. Without a URL the file refers to the
    environment variable B2D_POSTGRES_URL, so the password stays out of the file (every process that opens
    the instance, workers included, then needs that variable)."""
    url = with_psycopg2_dialect(postgres_url) if postgres_url else {"env": POSTGRES_URL_ENV}
    return {**instance_config(cores), "storage": {"postgres": {"postgres_url": url}}}


def with_psycopg2_dialect(url: str) -> str:
    """SQLAlchemy 2.1 reads a plain postgresql:// URL as psycopg 3, which dagster-postgres does not install
    (it brings psycopg2-binary): name the driver it has."""
    scheme, sep, rest = url.partition("://")
    return f"postgresql+psycopg2://{rest}" if sep and scheme in ("postgres", "postgresql") else url


def write_postgres_instance_yaml(dagster_home: Path, postgres_url: str | None = None) -> Path:
    """Write DAGSTER_HOME/dagster.yaml for Postgres storage (replacing one there: this is an explicit
    choice, unlike instance.ensure_instance_yaml). Readable by its owner only: it may hold a password."""
    path = Path(dagster_home) / "dagster.yaml"
    text = ("# written by b2d (b2d_pipeline/scale_out/instance_yaml.py): instance storage on PostgreSQL\n"
            + yaml.safe_dump(postgres_instance_config(postgres_url), sort_keys=False))
    with atomic_path(path) as tmp:
        # owner-only from its creation on, not after the password is in it
        with os.fdopen(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600), "w", encoding="utf-8") as f:
            f.write(text)
    return path


def require_instance_services(dagster_home: Path) -> None:
    """If DAGSTER_HOME's instance keeps its storage on Postgres, check the server answers (one-line error
    otherwise); call before DagsterInstance.get(), whose driver would retry and then print pages."""
    path = Path(dagster_home) / "dagster.yaml"
    if not path.exists():
        return
    storage = (yaml.safe_load(path.read_text()) or {}).get("storage") or {}
    postgres = storage.get("postgres")
    if not postgres:
        return
    url = postgres.get("postgres_url")
    if isinstance(url, dict):            # {"env": NAME}
        name = url.get("env", "")
        url = os.environ.get(name)
        if not url:
            raise ValueError(f"{path}: storage.postgres.postgres_url reads the environment variable {name}, "
                             f"which is not set (e.g. {name}=$(deploy/postgres.sh url))")
    if url is None:                      # postgres_db: {hostname, port, ...}
        db = postgres.get("postgres_db") or {}
        url = f"postgresql://{_plain(db.get('hostname', '127.0.0.1'))}:{_plain(db.get('port', 5432))}"
    require(POSTGRES, url, what=f"instance storage of {path}")


def _plain(value):
    return os.environ.get(value["env"], "") if isinstance(value, dict) else value
