"""Where the scale-out services are, and a check that one answers before it is used: a socket connect
(a second at most), so that a service that is down gives one line naming it and the command that starts
it, instead of a driver's retry loop and a multi-page traceback."""

from __future__ import annotations

import os
import socket
from dataclasses import dataclass
from urllib.parse import urlsplit

POSTGRES_URL_ENV = "B2D_POSTGRES_URL"
CELERY_BROKER_ENV = "B2D_CELERY_BROKER"
CELERY_BACKEND_ENV = "B2D_CELERY_BACKEND"
# deploy/redis.sh's defaults: broker and results in two databases of one server
DEFAULT_BROKER = "redis://127.0.0.1:6379/0"
DEFAULT_BACKEND = "redis://127.0.0.1:6379/1"


class ServiceUnavailable(RuntimeError):
    """A service the run needs does not answer; the message is one line."""


@dataclass(frozen=True)
class Service:
    name: str
    default_port: int
    script: str             # the project's start script, relative to the checkout
    port_env: str           # the script's port setting

    def start_command(self, port: int) -> str:
        prefix = "" if port == self.default_port else f"{self.port_env}={port} "
        return f"{prefix}{self.script} start"


POSTGRES = Service("Postgres", 5432, "deploy/postgres.sh", "B2D_PG_PORT")
REDIS = Service("Redis", 6379, "deploy/redis.sh", "B2D_REDIS_PORT")


def endpoint(service: Service, url: str) -> tuple[str, int]:
    parts = urlsplit(url)
    if not parts.scheme or not parts.hostname:
        raise ValueError(f"{service.name} URL {_without_password(url)!r}: expected scheme://host[:port]/..., "
                         f"e.g. {service.name.lower()}://127.0.0.1:{service.default_port}")
    return parts.hostname, parts.port or service.default_port


def require(service: Service, url: str, what: str = "", timeout: float = 1.0) -> None:
    """Raise ServiceUnavailable (one line) unless something accepts connections at the URL's host and port."""
    host, port = endpoint(service, url)
    try:
        socket.create_connection((host, port), timeout=timeout).close()
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        role = f" ({what})" if what else ""
        start = (f"start it with `{service.start_command(port)}`" if host in ("127.0.0.1", "localhost", "::1")
                 else f"start it on {host} or correct the URL")
        raise ServiceUnavailable(f"{service.name}{role} is not reachable at {host}:{port}: {reason.lower()}; "
                                 f"{start}") from None


def postgres_url() -> str:
    url = os.environ.get(POSTGRES_URL_ENV)
    if not url:
        raise ServiceUnavailable(f"{POSTGRES_URL_ENV} is not set; start Postgres with `deploy/postgres.sh start` "
                                 f"and set {POSTGRES_URL_ENV}=$(deploy/postgres.sh url)")
    return url


def celery_broker_url() -> str:
    return os.environ.get(CELERY_BROKER_ENV) or DEFAULT_BROKER


def celery_backend_url() -> str:
    return os.environ.get(CELERY_BACKEND_ENV) or DEFAULT_BACKEND


def _without_password(url: str) -> str:
    parts = urlsplit(url)
    return url.replace(f":{parts.password}@", ":***@") if parts.password else url
