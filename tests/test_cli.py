import json

from click.testing import CliRunner

import pytest

from b2d_cli.main import cli
from sim.registry import paper_settings
from sim.tasks import has_finished_plan, load_task
from teleop.demo_bench import not_run

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"


@pytest.fixture(params=["no plan", "draft plan"])
def unplanned(request, edited_task) -> str:
    """A paper task the scripted operator cannot demonstrate: its plan taken out, or marked a draft (every
    task in the catalog has a finished plan since stop 36)."""
    change = (lambda raw: raw.pop("demo_plan")) if request.param == "no plan" else \
        (lambda raw: raw.update(demo_plan_draft=True))
    task = edited_task("fridge_fruit_shelf_sorting", change)
    assert not has_finished_plan(task)
    return task


def test_list_json():
    runner = CliRunner()
    for kind in ("embodiments", "tasks", "settings", "profiles", "channels", "policies"):
        result = runner.invoke(cli, ["list", kind, "--json"])
        assert result.exit_code == 0, result.output
        rows = json.loads(result.output)
        assert isinstance(rows, list) and rows
    settings = json.loads(runner.invoke(cli, ["list", "settings", "--json"]).output)
    assert len(settings) == 26


def test_list_settings_says_which_can_be_recorded(unplanned):
    lines = CliRunner().invoke(cli, ["list", "settings"]).output.splitlines()
    assert lines[0].split() == ["key", "task", "embodiment", "available", "recordable", "draft_plan"]
    recordable = {line.split()[1]: line.split()[-2] for line in lines[1:]}
    draft = {line.split()[1]: line.split()[-1] for line in lines[1:]}
    assert len(lines) == 27 and recordable[TASK] == "yes" and recordable[unplanned] == "no"
    assert draft[unplanned] == ("yes" if load_task(unplanned).demo_plan else "no")


def test_unknown_name_is_a_clear_error(tmp_path):
    result = CliRunner().invoke(cli, ["record", "--task", "nope", "--embodiment", EMBODIMENT, "--out", str(tmp_path)])
    assert result.exit_code == 2 and "valid task names" in result.output


def test_record_replay_validate(tmp_path):
    runner = CliRunner()
    raw_dir, ep_dir = tmp_path / "raw", tmp_path / "episodes"
    result = runner.invoke(cli, ["record", "--task", TASK, "--embodiment", EMBODIMENT, "--episodes", "1",
                                 "--out", str(raw_dir), "--max-steps", "12"])
    assert result.exit_code == 0, result.output
    raw = sorted(raw_dir.glob("*.raw.h5"))
    assert len(raw) == 1
    result = runner.invoke(cli, ["replay", str(raw[0]), "--profile", "preview", "--out", str(ep_dir)])
    assert result.exit_code == 0, result.output
    episodes = sorted(ep_dir.glob("episode_*.hdf5"))
    assert len(episodes) == 1 and (ep_dir / "episode_manifest.json").exists()
    assert runner.invoke(cli, ["validate", str(episodes[0])]).exit_code == 0
    (tmp_path / "junk.hdf5").write_bytes(b"not hdf5")
    assert runner.invoke(cli, ["validate", str(tmp_path / "junk.hdf5")]).exit_code == 1


def test_record_refuses_a_task_without_a_demonstration_plan(tmp_path, unplanned):
    result = CliRunner().invoke(cli, ["record", "--task", unplanned, "--embodiment", EMBODIMENT,
                                      "--episodes", "1", "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert f"{unplanned}.yaml: field 'demo_plan" in result.output       # 'demo_plan' or 'demo_plan_draft'
    assert not list(tmp_path.iterdir())


def test_materialize_refuses_a_setting_the_operator_cannot_record(tmp_path, monkeypatch, unplanned):
    monkeypatch.setenv("B2D_DATA_ROOT", str(tmp_path))
    key = f"{unplanned}__{load_task(unplanned).paper_embodiment}"
    result = CliRunner().invoke(cli, ["materialize", "--setting", key])
    assert result.exit_code == 2
    assert f"unknown recordable setting '{key}'" in result.output and TASK in result.output
    assert not list(tmp_path.iterdir())


def test_bench_demos_rejects_unknown_names_and_says_why_a_setting_is_not_run(unplanned):
    setting = next(s for s in paper_settings() if s.task == unplanned)
    assert not_run(setting) == ("draft demo_plan (runs when its setting is named)" if load_task(unplanned).demo_plan
                                else "no demo_plan")
    result = CliRunner().invoke(cli, ["bench", "demos", "--setting", "nope__ur5_rh5dg2"])
    assert result.exit_code == 2 and "valid task names" in result.output
