"""The Dagster definitions load, and one materialize() of the whole chain works at the smallest size."""

import os
import subprocess
import sys

import dagster as dg
import pandas as pd

from b2d_pipeline.definitions import build_definitions, defs
from b2d_pipeline.chain import materialize_chain
from b2d_pipeline.settings import FactorySettings
SETTING = "citrus_plate_loading__ur5_rh5dg2"

ASSETS = {"setting_specs", "raw_recordings", "replays", "renders", "episodes", "policy_inputs", "act_checkpoint", "dp_checkpoint",
          "scripted_operator_rollouts", "act_rollouts", "dp_rollouts", "evaluation_table", "lerobot_dataset",
          "teleop_episodes"}


def test_definitions_load():
    keys = {k.to_user_string() for k in defs.resolve_asset_graph().get_all_asset_keys()}
    assert keys == ASSETS
    assert SETTING in defs.resolve_assets_def("raw_recordings").partitions_def.get_partition_keys()


def test_the_eta_is_a_lower_bound_until_every_remaining_job_has_a_time():
    from b2d_pipeline.chain import _eta

    assert _eta({}, ["produce_and_train"]) == "ETA ?"
    assert _eta({"produce_and_train": [100.0]}, ["produce_and_train", "evaluate_policies"]) == "ETA >= 1:40"
    assert _eta({"produce_and_train": [60.0, 120.0], "evaluate_policies": [30.0]},
                ["produce_and_train", "evaluate_policies", "evaluate_policies"]) == "ETA 2:30"


def test_profile_change_changes_render_code_version(tmp_path):
    preview = build_definitions(FactorySettings.from_env(data_root=tmp_path, profile="preview"))
    paper = build_definitions(FactorySettings.from_env(data_root=tmp_path, profile="paper"))
    for key in ("renders", "episodes"):
        a = preview.resolve_assets_def(key).code_versions_by_key[dg.AssetKey(key)]
        b = paper.resolve_assets_def(key).code_versions_by_key[dg.AssetKey(key)]
        assert a != b
    assert (preview.resolve_assets_def("replays").code_versions_by_key[dg.AssetKey("replays")]
            == paper.resolve_assets_def("replays").code_versions_by_key[dg.AssetKey("replays")])


def test_materialize_whole_chain(tmp_path):
    settings = FactorySettings.from_env(data_root=tmp_path, profile="preview", demo_episodes=1,
                                        eval_episodes=1, max_steps=12, train_steps=2)
    lines = []
    (tmp_path / "dagster_home").mkdir()
    with dg.instance_for_test(temp_dir=str(tmp_path / "dagster_home")) as instance:
        results = materialize_chain(settings, [SETTING], instance, channels=["none", "inv_equi"], log=lines.append,
                                    processes=2)
        runs = instance.get_runs()
        assert sorted(r.job_name for r in runs) == ["build_evaluation_table", "evaluate_policies",
                                                    "evaluate_policies", "produce_and_train"]
        from b2d_pipeline.chain import past_durations
        assert {job: len(times) for job, times in past_durations(instance, ["produce_and_train", "evaluate_policies"])
                .items()} == {"produce_and_train": 1, "evaluate_policies": 2}    # the next run's ETA from the start
    assert all(r.success for r in results)
    assert lines[0].startswith("[1/4] produce_and_train [citrus_plate_loading__ur5_rh5dg2]  elapsed 0:00")
    profile_hash = settings.profile.content_hash
    assert list((tmp_path / "episodes" / profile_hash / SETTING).glob("episode_*.hdf5"))
    for policy in ("act", "dp"):
        assert (tmp_path / "checkpoints" / f"{policy}_tiny" / SETTING / "model.safetensors").is_file()
    table = pd.read_parquet(tmp_path / "evaluation" / "evaluation_table.parquet")
    assert set(table["channel"]) == {"none", "inv_equi"}
    assert set(table["policy"]) == {"scripted_operator", "act_tiny", "dp_tiny"}
    assert {"SR", "LSCR", "N"} <= set(table.columns)
    assert (table["N"] == 1).all()


def test_a_changed_policy_config_changes_the_checkpoint_code_version(tmp_path):
    tiny = build_definitions(FactorySettings.from_env(data_root=tmp_path))
    paper = build_definitions(FactorySettings.from_env(data_root=tmp_path, policy_config="paper"))
    versions = [d.resolve_assets_def("act_checkpoint").code_versions_by_key[dg.AssetKey("act_checkpoint")]
                for d in (tiny, paper)]
    assert len(set(versions)) == 2


def test_run_parameters_are_dagster_config_with_the_settings_as_defaults(tmp_path):
    d = build_definitions(FactorySettings.from_env(data_root=tmp_path, demo_episodes=3, train_steps=7))
    fields = d.resolve_job_def("produce_and_train").run_config_schema.config_type.fields["ops"].config_type.fields
    recording = fields["raw_recordings"].config_type.fields["config"].config_type.fields
    assert recording["episodes"].default_value == 3 and "max_steps" in recording
    assert fields["act_checkpoint"].config_type.fields["config"].config_type.fields["steps"].default_value == 7


def test_bad_recording_fails_its_partition_and_keeps_the_rest(tmp_path, raw_path):
    settings = FactorySettings.from_env(data_root=tmp_path, profile="preview", demo_episodes=1, max_steps=12)
    raw_dir = tmp_path / "raw" / SETTING
    raw_dir.mkdir(parents=True)
    (raw_dir / "episode_0000.raw.h5").write_bytes(raw_path.read_bytes())
    (raw_dir / "episode_0001.raw.h5").write_bytes(raw_path.read_bytes()[:1000])    # truncated
    d = build_definitions(settings)
    with dg.DagsterInstance.ephemeral() as instance:
        result = dg.materialize(list(d.assets), selection=["replays"], partition_key=SETTING, instance=instance,
                                resources=d.resources, raise_on_error=False)
    assert not result.success
    failure = next(e for e in result.all_events if e.is_step_failure)
    assert "episode_0001.raw.h5" in str(failure.event_specific_data) and "truncated" in str(failure.event_specific_data)
    assert (tmp_path / "replays" / SETTING / "episode_0000.replay.h5").exists()
    assert not (tmp_path / "replays" / SETTING / "episode_0001.replay.h5").exists()


def test_dagster_home_follows_the_data_root(tmp_path):
    """Without DAGSTER_HOME, a fresh process loading the definitions keeps its run history under
    B2D_DATA_ROOT (a separate data root never mixes runs with the default one)."""
    env = {k: v for k, v in os.environ.items() if k != "DAGSTER_HOME"}
    env["B2D_DATA_ROOT"] = str(tmp_path)
    out = subprocess.run([sys.executable, "-c", "import os, b2d_pipeline.definitions; print(os.environ['DAGSTER_HOME'])"],
                         env=env, capture_output=True, text=True, check=True).stdout.strip()
    assert out == str(tmp_path / "dagster_home")


def test_the_project_writes_its_dagster_yaml_once(tmp_path):
    import yaml

    from b2d_pipeline.instance import ensure_instance_yaml

    path = ensure_instance_yaml(tmp_path / "home")
    config = yaml.safe_load(path.read_text())
    assert config["telemetry"] == {"enabled": False} and config["concurrency"]["runs"]["max_concurrent_runs"] >= 1
    assert config["concurrency"]["pools"]["default_limit"] == config["concurrency"]["runs"]["max_concurrent_runs"]
    with dg.DagsterInstance.from_config(str(tmp_path / "home")) as instance:   # Dagster accepts what b2d writes
        assert instance.run_coordinator is not None
    path.write_text("telemetry:\n  enabled: true\n")          # a user's own settings are kept
    ensure_instance_yaml(tmp_path / "home")
    assert path.read_text() == "telemetry:\n  enabled: true\n"


def test_the_run_plan_covers_every_policy_and_channel():
    from b2d_pipeline.chain import run_plan

    plan = run_plan(FactorySettings.from_env(), [SETTING], channels=["none", "inv_only"])
    assert [p[1] for p in plan] == ["produce_and_train", "evaluate_policies", "evaluate_policies",
                                    "build_evaluation_table"]
    jobs = {name: defs.resolve_job_def(name) for name in ("produce_and_train", "evaluate_policies")}
    assert {k.to_user_string() for k in jobs["evaluate_policies"].asset_layer.selected_asset_keys} == {
        "scripted_operator_rollouts", "act_rollouts", "dp_rollouts"}
    assert {k.to_user_string() for k in jobs["produce_and_train"].asset_layer.selected_asset_keys} == {
        "setting_specs", "raw_recordings", "replays", "renders", "episodes", "policy_inputs", "act_checkpoint",
        "dp_checkpoint"}


def test_an_empty_partition_fails_saying_why(tmp_path):
    """A setting with no recordings must not turn green with 0 episodes."""
    d = build_definitions(FactorySettings.from_env(data_root=tmp_path, profile="preview"))
    with dg.DagsterInstance.ephemeral() as instance:
        result = dg.materialize(list(d.assets), selection=["replays"], partition_key=SETTING, instance=instance,
                                resources=d.resources, raise_on_error=False)
    assert not result.success
    failure = str(next(e for e in result.all_events if e.is_step_failure).event_specific_data)
    assert "no *.raw.h5 files in" in failure and SETTING in failure and "raw_recordings" in failure


def test_partitions_cover_all_26_settings_and_an_unplanned_one_fails_saying_how_to_record_it(tmp_path, edited_task):
    from b2d_pipeline.partitions import recordable_setting_keys, setting_keys
    from sim.registry import paper_settings

    assert setting_keys() == [s.key for s in paper_settings()] and len(setting_keys()) == 26
    assert SETTING in recordable_setting_keys() and set(recordable_setting_keys()) <= set(setting_keys())
    # every task has a finished plan since stop 36: one stands in with its plan taken out
    task = edited_task("fridge_fruit_shelf_sorting", lambda raw: raw.pop("demo_plan"))
    unplanned = next(s for s in paper_settings() if s.task == task)
    assert unplanned.key not in recordable_setting_keys()
    d = build_definitions(FactorySettings.from_env(data_root=tmp_path, profile="preview"))
    with dg.DagsterInstance.ephemeral() as instance:
        result = dg.materialize(list(d.assets), selection=["raw_recordings"], partition_key=unplanned.key,
                                instance=instance, resources=d.resources, raise_on_error=False)
    assert not result.success
    failure = str(next(e for e in result.all_events if e.is_step_failure).event_specific_data)
    assert "has no demo_plan" in failure and "b2d teleop" in failure and f"tasks/{unplanned.task}.yaml" in failure


def test_renders_fan_out_one_step_per_replay_and_a_bad_replay_fails_only_itself(tmp_path, raw_path):
    from episodes.stages import replay_to_file

    settings = FactorySettings.from_env(data_root=tmp_path, profile="preview")
    replay_dir = tmp_path / "replays" / SETTING
    replay_to_file(raw_path, replay_dir / "episode_0000.replay.h5")
    (replay_dir / "episode_0001.replay.h5").write_bytes(b"not an HDF5 file")
    d = build_definitions(settings)
    with dg.DagsterInstance.ephemeral() as instance:
        result = dg.materialize(list(d.assets), selection=["renders"], partition_key=SETTING, instance=instance,
                                resources=d.resources, raise_on_error=False)
    steps = {e.step_key for e in result.all_events if e.event_type_value == "STEP_START"}
    assert steps == {"renders.list_replays", "renders.render_replay[episode_0000]",
                     "renders.render_replay[episode_0001]", "renders.gather_renders"}
    failure = str(next(e for e in result.all_events if e.is_step_failure).event_specific_data)
    assert "episode_0001.replay.h5" in failure and "1 succeeded" in failure
    render_dir = tmp_path / "renders" / settings.profile.content_hash / SETTING
    assert [p.name for p in render_dir.glob("*.h5")] == ["episode_0000.render.h5"]
    # the steps hand each other JSON, never a pickle
    outputs = list((tmp_path / "step_outputs").rglob("*"))
    assert any(p.suffix == ".json" for p in outputs) and not any(p.suffix in ("", ".pkl") and p.is_file() for p in outputs)
