"""A tiny partitioned asset graph that checks a scale-out setup end to end: one source, two branches that
can run side by side, a join. Each step records the host and process that ran it, so a run shows at a
glance whether the steps went to the workers (and to which); it writes no file and passes no value.
Launch `scale_out_probe_celery` for a partition once the workers are up (deploy/README.md)."""

import os
import socket
import time

import dagster as dg

from b2d_pipeline.scale_out.executors import executor_named

PROBE_PARTITIONS = dg.StaticPartitionsDefinition(["p0", "p1"])
STEP_SECONDS = 0.3      # long enough that the two branches overlap on two workers


def _ran_here(context: dg.AssetExecutionContext) -> dg.MaterializeResult:
    time.sleep(STEP_SECONDS)
    return dg.MaterializeResult(metadata={"host": socket.gethostname(), "pid": os.getpid(),
                                          "partition": context.partition_key})


@dg.asset(partitions_def=PROBE_PARTITIONS, group_name="scale_out_probe")
def probe_source(context: dg.AssetExecutionContext) -> dg.MaterializeResult:
    return _ran_here(context)


@dg.asset(partitions_def=PROBE_PARTITIONS, group_name="scale_out_probe", deps=[probe_source])
def probe_left(context: dg.AssetExecutionContext) -> dg.MaterializeResult:
    return _ran_here(context)


@dg.asset(partitions_def=PROBE_PARTITIONS, group_name="scale_out_probe", deps=[probe_source])
def probe_right(context: dg.AssetExecutionContext) -> dg.MaterializeResult:
    return _ran_here(context)


@dg.asset(partitions_def=PROBE_PARTITIONS, group_name="scale_out_probe", deps=[probe_left, probe_right])
def probe_join(context: dg.AssetExecutionContext) -> dg.MaterializeResult:
    return _ran_here(context)


PROBE_ASSETS = [probe_source, probe_left, probe_right, probe_join]


def probe_job(executor: str) -> dg.JobDefinition:
    job = dg.define_asset_job(f"scale_out_probe_{executor}", selection=dg.AssetSelection.groups("scale_out_probe"),
                              executor_def=executor_named(executor))
    return dg.Definitions(assets=PROBE_ASSETS, jobs=[job]).resolve_job_def(job.name)


# module-level targets for dg.reconstructable: workers rebuild the job by importing these
def celery_probe_job() -> dg.JobDefinition:
    return probe_job("celery")


def in_process_probe_job() -> dg.JobDefinition:
    return probe_job("in_process")


def multiprocess_probe_job() -> dg.JobDefinition:
    return probe_job("multiprocess")
