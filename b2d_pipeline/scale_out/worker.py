"""Start one Celery worker for b2d's steps: `python -m b2d_pipeline.scale_out.worker NAME [--concurrency N]`.

Checks that Redis and the instance's Postgres answer (one line otherwise), writes the worker's Celery
settings (the same broker and backend as the celery executor's) where dagster-celery's app reads them (a
`dagster_celery_config` module on PYTHONPATH, as `dagster-celery worker start` does), then becomes
`celery -A dagster_celery.app worker`: one process that a signal stops with its pool. One pool process per
core: a render or rollout step uses one.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from b2d_pipeline.scale_out.instance_yaml import require_instance_services
from b2d_pipeline.scale_out.services import REDIS, celery_backend_url, celery_broker_url, require
from episodes.atomic import write_text_atomic

# a busy worker takes no second step (acks_late + prefetch 1), so idle workers get the ready steps
WORKER_CELERY_SETTINGS = {"task_acks_late": True}


def celery_settings_module(broker: str, backend: str) -> str:
    """The text of `dagster_celery_config.py`: plain assignments of literals (repr), nothing else."""
    settings = {"broker_url": broker, "result_backend": backend, **WORKER_CELERY_SETTINGS}
    return "".join(f"{key} = {value!r}\n" for key, value in settings.items())


def worker_command(name: str, concurrency: int = 1, preload: tuple[str, ...] = (), loglevel: str = "WARNING") -> list[str]:
    """`preload`: modules imported once before the pool forks (the job's definitions), so a step does not
    pay the import."""
    celery = str(Path(sys.executable).parent / "celery")
    return [celery, "-A", "dagster_celery.app", "worker", "--prefetch-multiplier=1", f"--concurrency={concurrency}",
            "-n", f"{name}@%h", "-l", loglevel, *(["--include", ",".join(preload)] if preload else [])]


def prepare(name: str, concurrency: int = 1, preload: tuple[str, ...] = ()) -> tuple[list[str], dict[str, str]]:
    """The checked command and environment of one worker."""
    home = os.environ.get("DAGSTER_HOME")
    if not home:
        raise ValueError("DAGSTER_HOME is not set: a worker writes to the same instance as the run "
                         "(see b2d_pipeline/scale_out/instance_yaml.py)")
    require_instance_services(Path(home))
    broker, backend = celery_broker_url(), celery_backend_url()
    require(REDIS, broker, what="Celery broker")
    folder = Path(home) / "celery_worker"
    folder.mkdir(parents=True, exist_ok=True)
    write_text_atomic(folder / "dagster_celery_config.py", celery_settings_module(broker, backend))
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(folder), env.get("PYTHONPATH")) if p)
    return worker_command(name, concurrency, preload), env


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m b2d_pipeline.scale_out.worker", description=__doc__.split("\n")[0])
    parser.add_argument("name", help="worker name (the host name is appended: NAME@host)")
    parser.add_argument("--concurrency", type=int, default=1, help="steps at once (default 1)")
    parser.add_argument("--preload", action="append", default=[], metavar="MODULE",
                        help="import before the pool forks, e.g. b2d_pipeline.definitions (repeatable)")
    args = parser.parse_args(argv)
    try:
        command, env = prepare(args.name, args.concurrency, tuple(args.preload))
    except (RuntimeError, ValueError) as exc:
        sys.exit(f"b2d worker: {exc}")
    os.execve(command[0], command, env)


if __name__ == "__main__":
    main()
