"""When things run: the production job per setting, a nightly re-render of every setting under the
active profile, and the result table rebuilt automatically when new rollouts land."""

from __future__ import annotations

import dagster as dg

from b2d_pipeline.jobs import rerender_job
from b2d_pipeline.partitions import settings_partitions

@dg.schedule(job=rerender_job, cron_schedule="0 2 * * *", default_status=dg.DefaultScheduleStatus.STOPPED)
def nightly_rerender(context: dg.ScheduleEvaluationContext):
    # A plain ScheduleDefinition on a partitioned job requests no partition: ask for each one.
    for key in settings_partitions.get_partition_keys():
        yield dg.RunRequest(run_key=f"{key}-{context.scheduled_execution_time:%Y%m%d}", partition_key=key)


automation_sensor = dg.AutomationConditionSensorDefinition(
    "evaluation_automation", target=dg.AssetSelection.assets("evaluation_table"),
    default_status=dg.DefaultSensorStatus.RUNNING)
