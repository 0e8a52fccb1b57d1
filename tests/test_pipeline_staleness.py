"""Staleness follows content: an edited task file marks its own setting's recordings stale, no other's."""

import dagster as dg
import pytest
from dagster._core.definitions.data_version import StaleStatus
from dagster._utils.test.data_versions import get_stale_status_resolver   # Dagster's own test helper

from b2d_pipeline.definitions import build_definitions
from b2d_pipeline.settings import FactorySettings
from sim import setting_files
from sim.errors import UnknownNameError

EDITED, OTHER = "citrus_plate_loading__ur5_rh5dg2", "breadbasket_fast_food_loading__ur5_rh5dg2"


def test_a_settings_hash_covers_its_task_embodiment_arm_and_hand_files():
    files = setting_files.setting_source_files("citrus_plate_loading", "ur5_rh5dg2")
    assert {role: p.name for role, p in files.items()} == {
        "task": "citrus_plate_loading.yaml", "embodiment": "ur5_rh5dg2.yaml", "arm": "ur5.yaml", "hand": "rh5dg2.yaml"}
    same_hand = setting_files.setting_content_hash("ball_box_loading", "ur5_rh5dg2")
    assert setting_files.setting_content_hash("citrus_plate_loading", "ur5_rh5dg2") != same_hand
    assert same_hand == setting_files.setting_content_hash("ball_box_loading", "ur5_rh5dg2")
    with pytest.raises(UnknownNameError, match="citrus_plate_loading"):
        setting_files.setting_source_files("citrus_plate_loadin", "ur5_rh5dg2")


def test_content_hash_changes_with_any_byte(tmp_path):
    a, b = tmp_path / "a.yaml", tmp_path / "b.yaml"
    a.write_text("x: 1\n")
    b.write_text("y: 2\n")
    before = setting_files.content_hash({"task": a, "hand": b})
    b.write_text("y: 3\n")
    assert setting_files.content_hash({"task": a, "hand": b}) != before


def test_an_edited_task_marks_only_its_settings_recordings_stale(tmp_path, monkeypatch):
    settings = FactorySettings.from_env(data_root=tmp_path, profile="preview", demo_episodes=1, max_steps=3)
    defs = build_definitions(settings)
    assets = [a for a in defs.assets if a.key.to_user_string() in ("raw_recordings", "setting_specs")]
    recordings = dg.AssetKey("raw_recordings")
    with dg.DagsterInstance.ephemeral() as instance:
        for key in (EDITED, OTHER):
            result = dg.materialize(assets, selection=["setting_specs", "raw_recordings"], partition_key=key,
                                    instance=instance, resources=defs.resources)
            assert result.success
        resolver = get_stale_status_resolver(instance, assets)
        assert {k: resolver.get_status(recordings, k) for k in (EDITED, OTHER)} == {
            EDITED: StaleStatus.FRESH, OTHER: StaleStatus.FRESH}

        real = setting_files.setting_content_hash
        monkeypatch.setattr("b2d_pipeline.assets.catalog.setting_content_hash",
                            lambda task, emb: real(task, emb) + ("-edited" if task == "citrus_plate_loading" else ""))
        dg.materialize(assets, selection=["setting_specs"], instance=instance, partition_key=OTHER,
                       resources=defs.resources)   # an observation
        resolver = get_stale_status_resolver(instance, assets)
        assert resolver.get_status(recordings, EDITED) == StaleStatus.STALE
        assert resolver.get_status(recordings, OTHER) == StaleStatus.FRESH
        causes = resolver.get_stale_causes(recordings, EDITED)
        assert any("setting_specs" in str(c.dependency) for c in causes)


def test_a_profile_change_requests_re_renders_of_replayed_settings_only(tmp_path):
    """Declarative automation instead of a nightly re-render: a changed profile (the renders' code version)
    requests renders of every setting whose replays exist, and nothing while the profile stands still."""
    preview = build_definitions(FactorySettings.from_env(data_root=tmp_path, profile="preview"))
    paper = build_definitions(FactorySettings.from_env(data_root=tmp_path, profile="paper"))
    renders = dg.AssetKey("renders")
    with dg.DagsterInstance.ephemeral() as instance:
        for key in (EDITED, OTHER):     # two settings replayed (events recorded through Dagster's own API)
            for asset in ("replays", "renders"):
                instance.report_runless_asset_event(dg.AssetMaterialization(asset, partition=key))
        first = dg.evaluate_automation_conditions(defs=preview, instance=instance)
        steady = dg.evaluate_automation_conditions(defs=preview, instance=instance, cursor=first.cursor)
        assert steady.get_requested_partitions(renders) == set()
        changed = dg.evaluate_automation_conditions(defs=paper, instance=instance, cursor=steady.cursor)
        assert changed.get_requested_partitions(renders) == {EDITED, OTHER}
