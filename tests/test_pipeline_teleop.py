"""A live recording dropped into the watched folder becomes a dynamic partition and flows to its episode."""

import shutil

import dagster as dg

from b2d_pipeline.definitions import build_definitions
from b2d_pipeline.settings import FactorySettings
from episodes.validate import validate_episode

SETTING = "citrus_plate_loading__ur5_rh5dg2"
KEY = f"{SETTING}/episode_0000"


def _tick(defs, instance):
    sensor = defs.resolve_sensor_def("new_teleop_recordings")
    with dg.build_sensor_context(instance=instance, definitions=defs, resources=defs.resources) as context:
        return sensor(context)


def test_a_new_recording_becomes_a_partition_and_an_episode(tmp_path, raw_path):
    settings = FactorySettings.from_env(data_root=tmp_path, profile="preview")
    defs = build_definitions(settings)
    watched = tmp_path / "teleop" / SETTING
    watched.mkdir(parents=True)
    (watched / "notes.txt").write_text("not a recording")        # foreign files are ignored
    with dg.instance_for_test() as instance:
        assert _tick(defs, instance).run_requests == []
        shutil.copy(raw_path, watched / "episode_0000.raw.h5")
        result = _tick(defs, instance)
        [add] = result.dynamic_partitions_requests
        assert list(add.partition_keys) == [KEY]
        assert [r.partition_key for r in result.run_requests] == [KEY]

        instance.add_dynamic_partitions("teleop_recordings", [KEY])
        run = defs.resolve_job_def("ingest_teleop").execute_in_process(partition_key=KEY, instance=instance)
        assert run.success
        assert not _tick(defs, instance).dynamic_partitions_requests      # known now: no second partition
    episode = tmp_path / "teleop_episodes" / settings.profile.content_hash / SETTING / "episode_0000.hdf5"
    assert validate_episode(episode) == []
