"""Rollouts fan out: a (setting, channel) cell runs one step per chunk of episodes, and the records file
is the same however the episodes are chunked."""

import dagster as dg
import pandas as pd

from b2d_pipeline.definitions import build_definitions
from b2d_pipeline.partitions import setting_channel_key
from b2d_pipeline.settings import FactorySettings

SETTING = "citrus_plate_loading__ur5_rh5dg2"
ASSET = "scripted_operator_rollouts"


def _run(tmp_path, per_step: int):
    settings = FactorySettings.from_env(data_root=tmp_path, profile="preview")
    d = build_definitions(settings)
    config = {"ops": {ASSET: {"ops": {f"plan_{ASSET}": {"config": {"episodes": 3, "max_steps": 4,
                                                                   "episodes_per_step": per_step}}}}}}
    with dg.DagsterInstance.ephemeral() as instance:
        result = dg.materialize(list(d.assets), selection=[ASSET], partition_key=setting_channel_key(SETTING, "inv_equi"),
                                instance=instance, resources=d.resources, run_config=config)
    steps = sorted(e.step_key for e in result.all_events if e.event_type_value == "STEP_START")
    path = tmp_path / "evaluation" / "rollouts" / "scripted_operator" / SETTING / "inv_equi.parquet"
    return steps, path


def test_a_cell_runs_one_step_per_chunk_and_the_file_does_not_depend_on_the_chunking(tmp_path):
    steps, chunked = _run(tmp_path / "a", per_step=2)
    assert steps == [f"{ASSET}.gather_{ASSET}", f"{ASSET}.plan_{ASSET}", f"{ASSET}.run_{ASSET}[episodes_00000]",
                     f"{ASSET}.run_{ASSET}[episodes_00002]"]
    steps, whole = _run(tmp_path / "b", per_step=10)
    assert len(steps) == 3
    assert pd.read_parquet(chunked)["episode"].tolist() == [0, 1, 2]
    assert chunked.read_bytes() == whole.read_bytes()
