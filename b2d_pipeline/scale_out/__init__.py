"""Scale-out on existing engines: a Dagster instance on PostgreSQL (runs, events, schedules), steps on
Celery workers through Redis, and the Kubernetes deployment in deploy/k8s. The services themselves are
Debian's, started by deploy/postgres.sh and deploy/redis.sh; this package only points Dagster at them and
says in one line which one is down and how to start it."""

from b2d_pipeline.scale_out.executors import EXECUTORS, executor_named
from b2d_pipeline.scale_out.instance_yaml import postgres_instance_config, write_postgres_instance_yaml
from b2d_pipeline.scale_out.services import POSTGRES, REDIS, ServiceUnavailable, require

__all__ = ["EXECUTORS", "POSTGRES", "REDIS", "ServiceUnavailable", "executor_named", "postgres_instance_config",
           "require", "write_postgres_instance_yaml"]
