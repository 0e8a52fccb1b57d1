"""The asset checks run per setting partition, inside the job that materializes it, and fail on what
they are there to catch: an empty partition, a blank frame, a replay beyond its drift bound."""

import json
import shutil

import dagster as dg
import h5py
import numpy as np
import hdf5plugin  # noqa: F401  (the episodes' compression filters)

from b2d_pipeline.definitions import build_definitions
from b2d_pipeline.settings import FactorySettings
from episodes.frame_checks import frame_problems

SETTING = "citrus_plate_loading__ur5_rh5dg2"
CHECKS = {"episodes_match_schema", "episode_frames_are_valid", "replays_within_drift_bound"}


def _materialize(d, selection, partition):
    with dg.DagsterInstance.ephemeral() as instance:
        return dg.materialize([*d.assets, *d.asset_checks], selection=selection, partition_key=partition,
                              instance=instance, resources=d.resources, raise_on_error=False)


def _check_again(d, partition):
    """The project's `check_episodes` job: the checks alone, nothing re-materialized."""
    with dg.DagsterInstance.ephemeral() as instance:
        return d.resolve_job_def("check_episodes").execute_in_process(partition_key=partition, instance=instance,
                                                                      raise_on_error=False)


def _checks(result) -> dict:
    return {e.asset_check_evaluation_data.check_name: e.asset_check_evaluation_data
            for e in result.all_events if e.event_type_value == "ASSET_CHECK_EVALUATION"}



def test_checks_run_per_partition_in_the_production_job_and_catch_bad_frames_and_drift(tmp_path, raw_dir):
    settings = FactorySettings.from_env(data_root=tmp_path, profile="preview")
    shutil.copytree(raw_dir, tmp_path / "raw" / SETTING)
    d = build_definitions(settings)
    job_checks = d.resolve_job_def("produce_episodes").asset_layer.asset_graph.asset_check_keys
    assert {k.name for k in job_checks} >= CHECKS
    result = _materialize(d, ["replays", "renders", "episodes"], SETTING)
    assert result.success
    found = _checks(result)
    assert set(found) == CHECKS and all(c.passed for c in found.values())
    assert found["episodes_match_schema"].metadata["checked"].value == 2
    fidelity = found["replays_within_drift_bound"].metadata["fidelity"].value
    assert sorted(fidelity) == ["episode_0000.replay.h5", "episode_0001.replay.h5"]

    # a blank camera frame in one episode, and a replay that drifted beyond its bound
    episode = sorted((tmp_path / "episodes" / settings.profile.content_hash / SETTING).glob("episode_*.hdf5"))[0]
    with h5py.File(episode, "r+") as f:
        camera = sorted(f["cameras"])[0]
        rgb = f[f"cameras/{camera}/rgb"]
        rgb[1] = np.zeros_like(rgb[1])
    assert frame_problems(episode) == [f"cameras/{camera}/rgb: one flat colour (nothing drawn) on frames 1"]
    replay = tmp_path / "replays" / SETTING / "episode_0001.replay.h5"
    with h5py.File(replay, "r+") as f:
        recorded = json.loads(f.attrs["fidelity"])
        f.attrs["fidelity"] = json.dumps({**recorded, "frames_over_bound": 4, "max_object_position_drift_m": 0.2})
    found = _checks(_check_again(d, SETTING))
    assert not found["episode_frames_are_valid"].passed
    assert list(found["episode_frames_are_valid"].metadata["problems"].value) == [str(episode)]
    assert not found["replays_within_drift_bound"].passed
    drift = found["replays_within_drift_bound"].metadata["problems"].value
    assert list(drift) == [str(replay)] and "4 frames drift beyond" in drift[str(replay)][0]
    assert not found["episodes_match_schema"].passed      # the edit no longer matches the manifest's digests


def test_an_empty_partition_fails_its_checks_saying_why(tmp_path):
    settings = FactorySettings.from_env(data_root=tmp_path, profile="preview")
    d = build_definitions(settings)
    found = _checks(_check_again(d, SETTING))
    assert set(found) == CHECKS and not any(c.passed for c in found.values())
    problems = found["replays_within_drift_bound"].metadata["problems"].value
    assert problems == {str(tmp_path / "replays" / SETTING): ["no replays in this partition"]}
