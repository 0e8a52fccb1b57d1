"""The CPU pool: across steps and runs at most one CPU-bound step per core, as the project's dagster.yaml
sets it (b2d_pipeline/instance.py); every asset that simulates, renders, trains or rolls out is in it."""

from pathlib import Path

import dagster as dg
import pytest

from b2d_pipeline.assets.common import CPU_POOL
from b2d_pipeline.definitions import defs
from b2d_pipeline.instance import instance_config

TESTS = Path(__file__).parent
LIGHT = {"setting_specs", "evaluation_table"}      # bookkeeping: observation of files, the table


def _intervals(instance, run_id) -> list[tuple[float, float]]:
    starts, ends = {}, {}
    for entry in instance.all_logs(run_id):
        kind = entry.dagster_event.event_type_value if entry.is_dagster_event else None
        if kind == "STEP_START":
            starts[entry.step_key] = entry.timestamp
        if kind == "STEP_SUCCESS":
            ends[entry.step_key] = entry.timestamp
    return sorted((starts[k], ends[k]) for k in starts)


@pytest.mark.parametrize("cores, overlap", [(1, False), (2, True)])
def test_the_project_instance_gives_the_cpu_pool_one_step_per_core(tmp_path, cores, overlap):
    with dg.instance_for_test(temp_dir=str(tmp_path), overrides=instance_config(cores)) as instance:
        # the step processes import the job from this folder (tests/ is no package)
        job = dg.build_reconstructable_job("pool_probe_job", "job", reconstructor_working_directory=str(TESTS))
        result = dg.execute_job(job, instance)
        assert result.success
        (a_start, a_end), (b_start, _) = _intervals(instance, result.run_id)
    assert (b_start < a_end) is overlap


def test_every_cpu_bound_asset_is_in_the_pool():
    for key in defs.resolve_asset_graph().get_all_asset_keys():
        pools = defs.resolve_assets_def(key).node_def.pools
        assert (CPU_POOL in pools) is (key.to_user_string() not in LIGHT), key.to_user_string()
