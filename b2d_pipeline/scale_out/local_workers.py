"""Celery workers on this host as subprocesses (`python -m b2d_pipeline.scale_out.worker NAME`, which
becomes the celery main process): started together, ready when each answers a ping through the broker,
stopped together. Each is its own process group, so that a stop reaches its pool children too. Used by
the tests and the benchmark; on a cluster each host starts its own worker instead."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


class LocalWorkers:
    def __init__(self, names: list[str], env: dict[str, str], log_dir: Path, preload: tuple[str, ...] = ()):
        self.names, self.log_dir, self.procs = names, Path(log_dir), []
        preload_args = [a for module in preload for a in ("--preload", module)]
        for name in names:
            with open(self.log_dir / f"{name}.log", "w") as log:
                self.procs.append(subprocess.Popen(
                    [sys.executable, "-m", "b2d_pipeline.scale_out.worker", name, *preload_args], env=env, cwd=REPO,
                    stdout=log, stderr=subprocess.STDOUT, start_new_session=True))

    def wait_ready(self, broker: str, timeout: float = 60.0) -> list[str]:
        """The workers' full names (NAME@host), once every one answers; an error with its log if one exits."""
        from celery import Celery

        app = Celery(broker=broker)
        deadline, answered = time.monotonic() + timeout, []
        while time.monotonic() < deadline:
            for proc, name in zip(self.procs, self.names):
                if proc.poll() is not None:
                    log = (self.log_dir / f"{name}.log").read_text()[-2000:]
                    raise RuntimeError(f"worker {name} exited with {proc.returncode}: {log}")
            answered = sorted(k for reply in app.control.ping(timeout=0.5) for k in reply)
            if len(answered) == len(self.names):
                return answered
        raise TimeoutError(f"only {answered} of {self.names} answered within {timeout} s")

    def stop(self, timeout: float = 20.0) -> None:
        for proc in self.procs:
            _signal_group(proc, signal.SIGTERM)
        for proc in self.procs:
            try:
                proc.wait(timeout=timeout)      # celery's warm shutdown stops and reaps its pool
            except subprocess.TimeoutExpired:
                _signal_group(proc, signal.SIGKILL)
                proc.wait()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()


def _signal_group(proc: subprocess.Popen, signum: int) -> None:
    try:
        os.killpg(proc.pid, signum)
    except ProcessLookupError:
        pass
