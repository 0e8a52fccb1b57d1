"""The Dagster asset exports a setting's episodes, kept fresh with them and outside every job."""

import json
import shutil

import dagster as dg
from foundation_demos import SETTING

from b2d_pipeline.definitions import build_definitions
from b2d_pipeline.settings import FactorySettings

KEY = dg.AssetKey("lerobot_dataset")


def test_the_asset_exports_a_settings_episodes(export_episodes, tmp_path):
    settings = FactorySettings.from_env(data_root=tmp_path, profile="policy_tiny")
    episode_dir = tmp_path / "episodes" / settings.profile.content_hash / SETTING
    episode_dir.mkdir(parents=True)
    for path in export_episodes:
        shutil.copy(path, episode_dir / path.name)
    defs = build_definitions(settings)
    with dg.DagsterInstance.ephemeral() as instance:
        result = dg.materialize(list(defs.assets), selection=[KEY], partition_key=SETTING, instance=instance,
                                resources=defs.resources)
    assert result.success
    out = tmp_path / "lerobot" / "v2.1" / settings.profile.content_hash / SETTING
    info = json.loads((out / "meta/info.json").read_text())
    assert info["total_episodes"] == len(export_episodes) and (out / "meta/modality.json").exists()
    event = result.get_asset_materialization_events()[0].materialization
    assert event.metadata["episodes"].value == len(export_episodes)


def test_the_asset_follows_the_episodes_and_no_job_runs_it(tmp_path):
    defs = build_definitions(FactorySettings.from_env(data_root=tmp_path))
    asset = defs.resolve_assets_def(KEY)
    assert dg.AssetKey("episodes") in asset.asset_deps[KEY]
    assert asset.automation_conditions_by_key[KEY] is not None
    for job in defs.get_repository_def().get_all_jobs():
        if not job.name.startswith("__"):          # Dagster's implicit all-assets job
            assert KEY not in job.asset_layer.selected_asset_keys, job.name
