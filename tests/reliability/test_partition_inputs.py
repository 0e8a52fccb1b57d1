"""Issue 23, item 4, in the pipeline: a foreign file in a partition's raw folder fails the partition by
name instead of being taken in; the good recordings are still replayed."""

import dagster as dg

from b2d_pipeline.definitions import build_definitions
from b2d_pipeline.settings import FactorySettings

SETTING = "citrus_plate_loading__ur5_rh5dg2"


def test_a_foreign_file_in_the_raw_folder_is_refused_by_name(tmp_path, raw_path):
    settings = FactorySettings.from_env(data_root=tmp_path, profile="preview", demo_episodes=1, max_steps=12)
    raw_dir = tmp_path / "raw" / SETTING
    raw_dir.mkdir(parents=True)
    (raw_dir / "episode_0000.raw.h5").write_bytes(raw_path.read_bytes())
    (raw_dir / "episode_0000 (copy).raw.h5").write_bytes(raw_path.read_bytes())     # a careless copy
    d = build_definitions(settings)
    with dg.DagsterInstance.ephemeral() as instance:
        result = dg.materialize(list(d.assets), selection=["replays"], partition_key=SETTING, instance=instance,
                                resources=d.resources, raise_on_error=False)
    assert not result.success
    failure = str(next(e for e in result.all_events if e.is_step_failure).event_specific_data)
    assert "episode_0000 (copy).raw.h5: field '<file name>'" in failure
    assert sorted(p.name for p in (tmp_path / "replays" / SETTING).iterdir()) == ["episode_0000.replay.h5"]
