"""The executor a job's steps run on, chosen by name: default (Dagster's own: multiprocess, or in_process by
run config, as chain.py configures it), in_process, multiprocess (one host), celery (workers on any host,
through Redis) or k8s (one Kubernetes Job per step). The celery executor here is dagster-celery's with one
addition: when a run starts, before any step is submitted, it checks that the broker answers, so a Redis
that is down is one line naming it and the command that starts it (dagster-celery alone waits and retries)."""

from __future__ import annotations

import warnings
from typing import Callable

import dagster as dg

from b2d_pipeline.scale_out.services import REDIS, celery_backend_url, celery_broker_url, require


def _celery() -> dg.ExecutorDefinition:
    try:
        from dagster_celery.executor import CELERY_CONFIG, CeleryExecutor
    except ImportError as exc:
        raise ImportError("the celery executor needs dagster-celery: pip install -e '.[scale]'") from exc
    from dagster._core.execution.retries import RetryMode

    schema = {**CELERY_CONFIG,
              "broker": dg.Field(dg.StringSource, is_required=False,
                                 description="Celery broker URL (default: $B2D_CELERY_BROKER or redis://127.0.0.1:6379/0)"),
              "backend": dg.Field(dg.StringSource, is_required=False,
                                  description="Celery results URL (default: $B2D_CELERY_BACKEND or redis://127.0.0.1:6379/1)")}

    @dg.executor(name="celery", config_schema=schema, requirements=dg.multiple_process_executor_requirements())
    def checked_celery_executor(init_context):
        config = init_context.executor_config
        broker = config.get("broker") or celery_broker_url()
        backend = config.get("backend") or celery_backend_url()
        if broker.startswith("redis"):
            require(REDIS, broker, what="Celery broker")
        if backend.startswith("redis"):
            require(REDIS, backend, what="Celery result backend")
        # dagster-celery registers its one task again for every step it submits; Celery 5.7 warns each time
        warnings.filterwarnings("ignore", message="Task name 'execute_plan' is already registered")
        return CeleryExecutor(broker=broker, backend=backend, config_source=config.get("config_source"),
                              include=config.get("include"), retries=RetryMode.from_config(config["retries"]))

    return checked_celery_executor


def _k8s() -> dg.ExecutorDefinition:
    try:
        from dagster_k8s import k8s_job_executor
    except ImportError as exc:
        raise ImportError("the k8s executor needs dagster-k8s: pip install -e '.[scale]'") from exc
    return k8s_job_executor


EXECUTORS: dict[str, Callable[[], dg.ExecutorDefinition]] = {
    "default": lambda: dg.multi_or_in_process_executor,
    "in_process": lambda: dg.in_process_executor,
    "multiprocess": lambda: dg.multiprocess_executor,
    "celery": _celery,
    "k8s": _k8s,
}


def executor_named(name: str) -> dg.ExecutorDefinition:
    if name not in EXECUTORS:
        raise KeyError(f"unknown executor {name!r}; valid names: {', '.join(EXECUTORS)}")
    return EXECUTORS[name]()
