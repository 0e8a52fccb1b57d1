"""Two one-and-a-half-second steps in the CPU pool, side by side if the pool lets them: a job the step
processes can import on their own (it imports nothing but Dagster and the pool's name)."""

import time

import dagster as dg

from b2d_pipeline.assets.common import CPU_POOL


@dg.op(pool=CPU_POOL)
def busy_a() -> None:
    time.sleep(1.5)


@dg.op(pool=CPU_POOL)
def busy_b() -> None:
    time.sleep(1.5)


@dg.job(executor_def=dg.multiprocess_executor.configured({"max_concurrent": 2}))
def two_busy_steps():
    busy_a()
    busy_b()


def job() -> dg.JobDefinition:
    return two_busy_steps
