"""Run the whole chain for settings through the project's Dagster jobs, in dependency order: per setting
`produce_and_train` (demonstrations to checkpoints), then `evaluate_policies` for each (setting, channel),
then `build_evaluation_table`. Each run goes on the instance under the job's name (the UI lists it) with
Dagster's multiprocess executor, so independent steps (renders beside policy inputs, ACT beside DP, one
policy's rollouts beside another's) use both cores. Dagster's own log lines go to the run storage, not
the terminal; the terminal shows one progress line per run: done/total, job and partition, elapsed, ETA.
"""

from __future__ import annotations

import contextlib
import os
import signal
import time

import dagster as dg

from b2d_pipeline.definitions import build_definitions
from b2d_pipeline.partitions import setting_channel_key, setting_channel_partitions
from b2d_pipeline.run_config import job_run_config
from b2d_pipeline.settings import FactorySettings
from sim.registry import channel_names

QUIET_LOGS = {"loggers": {"console": {"config": {"log_level": "ERROR"}}}}


# the project's jobs `b2d materialize` runs, in dependency order per setting
JOBS = ("produce_and_train", "evaluate_policies", "build_evaluation_table")


def job_for(name: str, **env: str) -> dg.JobDefinition:
    """The project's job `name` under the settings `env` (FactorySettings.to_env). The settings travel in
    the job's pointer, so the run and every step process (forked, spawned or on a Celery worker) build the
    same definitions, and Dagster's cache of the last loaded job per pointer never hands a run the job of
    other settings (it did: a Celery test's job, executor and all, to a later run in the same process)."""
    return build_definitions(FactorySettings.from_mapping(env)).resolve_job_def(name)


def reconstructable_job(name: str, settings: FactorySettings):
    """The job `name` under `settings`, as Dagster loads it in every process of a run."""
    return dg.build_reconstructable_job("b2d_pipeline.chain", "job_for", reconstructable_args=(name,),
                                        reconstructable_kwargs=settings.to_env())


def run_plan(settings: FactorySettings, setting_keys: list[str], channels: list[str] | None = None) -> list[tuple]:
    """[(setting or None, job name, partition key or None)] in the order they run."""
    plan = []
    for key in setting_keys:
        plan.append((key, "produce_and_train", key))
        plan += [(key, "evaluate_policies", setting_channel_key(key, c)) for c in channels or channel_names()]
    plan.append((None, "build_evaluation_table", None))
    return plan


@contextlib.contextmanager
def _environment(values: dict[str, str]):
    saved = {k: os.environ.get(k) for k in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def past_durations(instance: dg.DagsterInstance, jobs, runs_per_job: int = 5) -> dict[str, list[float]]:
    """Wall times of the last successful runs of each job on this instance (the ETA's prior)."""
    found = {}
    for job in jobs:
        records = instance.get_run_records(dg.RunsFilter(job_name=job, statuses=[dg.DagsterRunStatus.SUCCESS]),
                                           limit=runs_per_job)
        times = [r.end_time - r.start_time for r in records if r.start_time and r.end_time]
        if times:
            found[job] = times
    return found


def _eta(durations: dict[str, list[float]], remaining: list[str]) -> str:
    """Remaining runs at the mean time of the job's runs so far (this invocation's, else the instance's
    earlier ones). A job that has never run here is not guessed from other jobs (that misled by minutes):
    while there is one the ETA is a lower bound ("ETA >= m:ss"), or "ETA ?" when nothing is known."""
    known = [sum(durations[job]) / len(durations[job]) for job in remaining if job in durations]
    if not known:
        return "ETA ?"
    bound = ">= " if len(known) < len(remaining) else ""
    return f"ETA {bound}{_clock(sum(known))}"


def _clock(seconds: float) -> str:
    return f"{int(seconds) // 60}:{int(seconds) % 60:02d}"


@contextlib.contextmanager
def signal_handlers_kept(signals=(signal.SIGTERM, signal.SIGINT)):
    """Put these signals' handlers back as they were after a Dagster run in this process. Dagster's
    interrupt handling (dagster/_utils/interrupts.py) leaves SIGTERM mapped to whatever SIGINT's handler
    was, and a background job of a non-interactive shell has SIGINT ignored: after one run the process,
    and every child it starts later, would ignore SIGTERM for good."""
    saved = {sig: signal.getsignal(sig) for sig in signals}
    try:
        yield
    finally:
        for sig, handler in saved.items():
            if handler is not None:               # None: set from outside Python; leave it
                signal.signal(sig, handler)


def materialize_chain(settings: FactorySettings, setting_keys: list[str], instance: dg.DagsterInstance,
                      channels: list[str] | None = None, log=print, processes: int | None = None) -> list:
    """Run the plan on `instance` (a persistent one: step processes write to it). `processes`: steps run
    side by side at most (default: the machine's cores; 1 runs each run in one process)."""
    processes = processes or os.cpu_count() or 1
    # forkserver: step processes fork from one that has imported the project already (~2 s saved a step),
    # and torch with the models (imported by the training and rollout steps only, ~3-7 s each otherwise)
    executor = ({"multiprocess": {"max_concurrent": processes, "start_method": {"forkserver": {"preload_modules": [
                    "b2d_pipeline.definitions", "policies.models.act", "policies.models.diffusion"]}}}}
                if processes > 1 else {"in_process": {}})
    defs = build_definitions(settings)
    # another executor (celery, k8s: B2D_EXECUTOR) takes its own config; the default one is sized here
    execution = {"execution": {"config": executor}} if settings.executor == "default" else {}
    run_configs = {job: {**QUIET_LOGS, **execution,
                         "ops": job_run_config(list(defs.resolve_job_def(job).graph.node_dict), settings)}
                   for job in JOBS}
    plan = run_plan(settings, setting_keys, channels)
    results, failed_settings, started = [], set(), time.perf_counter()
    durations, timed_here = past_durations(instance, JOBS), set()
    with _environment(settings.to_env()):
        for done, (setting, job, partition) in enumerate(plan):
            if setting in failed_settings:
                continue                              # its production failed: nothing to evaluate
            elapsed = time.perf_counter() - started
            eta = _eta(durations, [j for _, j, _ in plan[done:]])
            where = f" [{partition}]" if partition else ""
            log(f"[{done + 1}/{len(plan)}] {job}{where}  elapsed {_clock(elapsed)}  {eta}")
            tags = (setting_channel_partitions.get_tags_for_partition_key(partition)
                    if isinstance(partition, dg.MultiPartitionKey) else {"dagster/partition": partition} if partition
                    else {})
            t0 = time.perf_counter()
            with signal_handlers_kept():
                result = dg.execute_job(reconstructable_job(job, settings), instance, run_config=run_configs[job],
                                        tags=tags)
            if job not in timed_here:                 # this machine, this size: forget the older runs
                durations[job], timed_here = [], timed_here | {job}
            durations[job].append(time.perf_counter() - t0)
            results.append(result)
            if not result.success:
                for event in result.all_events:
                    if event.is_step_failure:
                        message = str(event.event_specific_data.error.message).strip()
                        log(f"  failed: {event.step_key}: {message[:500]}")
                if job == "produce_and_train":
                    failed_settings.add(setting)
    log(f"done in {_clock(time.perf_counter() - started)}")
    return results
