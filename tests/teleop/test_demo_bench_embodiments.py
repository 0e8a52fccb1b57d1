"""`b2d bench demos --embodiment ...`: a task's plan on other embodiments (teleop/cross_embodiment.py).
Real scenes and episodes, kept to a few control steps."""

import json

import pytest
from click.testing import CliRunner

from b2d_cli.main import cli
from sim.errors import UnknownNameError
from sim.registry import names
from sim.tasks import load_task
from teleop.cross_embodiment import (decided, failure_cause, markdown_table, parse_embodiments, parse_tasks,
                                     plan_reach, recordable_tasks, run_cell, run_cross_embodiment_bench,
                                     stray_sides)

TASK = "citrus_plate_loading"
PAPER, OTHER = "ur5_rh5dg2", "xarm7_leap"


def test_embodiment_names_all_list_and_unknown():
    assert parse_embodiments("all") == names("embodiments") and len(names("embodiments")) == 12
    assert parse_embodiments(f"{OTHER}, {PAPER},{OTHER}") == [OTHER, PAPER]
    with pytest.raises(UnknownNameError, match="valid embodiment names: .*ur5_shadow"):
        parse_embodiments(f"{PAPER},ur5_nope")


def test_task_names_from_keys_or_tasks():
    assert parse_tasks([f"{TASK}__{OTHER}", "trash_disposal", TASK]) == [TASK, "trash_disposal"]
    assert parse_tasks(None) == recordable_tasks() and TASK in recordable_tasks()
    assert all(load_task(t).demo_plan for t in recordable_tasks())
    with pytest.raises(UnknownNameError, match="valid task names"):
        parse_tasks(["nope"])
    with pytest.raises(UnknownNameError, match="valid embodiment names"):
        parse_tasks([f"{TASK}__nope"])


def test_majority_is_decided_early_only_when_settled():
    assert decided(2, 0, 3) and decided(0, 2, 3) and not decided(1, 1, 3)
    assert decided(0, 6, 12) and not decided(6, 5, 12) and decided(7, 0, 12)


def test_a_cell_stops_once_its_majority_is_decided():
    # 2 control steps: every seed fails, so a majority of 3 is lost after 2 failures
    cell = run_cell(TASK, OTHER, seeds=3, max_steps=2, stop_when_decided=True, dry_run=False)
    assert (cell["seeds"], cell["seeds_planned"], cell["successes"]) == (2, 3, 0)
    assert cell["decided_early"] and not cell["majority"]
    cell = run_cell(TASK, OTHER, seeds=2, max_steps=2, stop_when_decided=True, dry_run=False)
    assert cell["seeds"] == 1 and cell["decided_early"]       # of 2, one failure already loses the majority


def test_bench_runs_every_cell_and_tables_them():
    result = run_cross_embodiment_bench([TASK], [PAPER, OTHER], seeds=1, max_steps=3, dry_run=False)
    assert result["tasks"] == [TASK] and result["embodiments"] == [PAPER, OTHER]
    assert [(c["embodiment"], c["seeds"], c["paper"], c["errors"]) for c in result["cells"]] == [
        (PAPER, 1, True, []), (OTHER, 1, False, [])]
    assert result["table"] == {TASK: {PAPER: "0/1", OTHER: "0/1"}}   # 3 steps: no success yet
    assert result["embodiments_with_majority"] == {TASK: 0} and result["tasks_reaching_goal"] == []
    assert result["per_embodiment"][OTHER] == {"successes": 0, "episodes": 1, "tasks_with_majority": 0,
                                               "arm_stray_tasks": []}      # no dry run asked for
    assert result["failures_by_cause"] == {}
    lines = markdown_table(result).splitlines()
    assert lines[0] == f"| task | {PAPER} | {OTHER} | majority on |"
    assert lines[2] == f"| {TASK} | **0/1** | 0/1 | 0 |"


def test_cells_in_two_processes_are_the_cells_in_one():
    """`--workers 2`: the same cells, in the same order, whichever process ran each."""
    def without_time(result):
        return [{k: v for k, v in c.items() if k != "cpu_s"} for c in result["cells"]]
    one = run_cross_embodiment_bench([TASK], [PAPER, OTHER], seeds=1, max_steps=3, dry_run=False)
    two = run_cross_embodiment_bench([TASK], [PAPER, OTHER], seeds=1, max_steps=3, dry_run=False, processes=2)
    assert without_time(two) == without_time(one) and two["table"] == one["table"]


def test_a_bad_cell_reports_its_error():
    """A cell whose episodes fail (no control step to write) reports each seed's error; the bench goes on."""
    cell = run_cell(TASK, OTHER, seeds=2, max_steps=0, dry_run=False)
    assert cell["seeds"] == 2 and cell["successes"] == 0 and len(cell["errors"]) == 2
    assert all("at least one control step" in e for e in cell["errors"])


def test_a_named_draft_plan_runs(edited_task):
    """A draft plan (`demo_plan_draft: true`) runs when its task is named, and is left out of 'all'."""
    draft = edited_task("fridge_fruit_shelf_sorting", lambda raw: raw.update(demo_plan_draft=True))
    assert load_task(draft).demo_plan_draft and draft not in recordable_tasks()
    result = run_cross_embodiment_bench([draft], [OTHER], seeds=1, max_steps=2)
    assert result["without_plan"] == [] and len(result["cells"]) == 1 and not result["cells"][0]["errors"]


def test_plan_dry_run_follows_the_paper_embodiments_path():
    cell = run_cell(TASK, PAPER, seeds=1, max_steps=2)
    reach = cell["plan_reach"]
    assert set(reach) == {"left", "right"} and cell["ik_off_path"] == [] and cell["arm_strays"] == []
    assert all(r["tracked_steps"] > 100 and r["worst_m"] < 0.01 for r in reach.values())
    assert cell["failure_cause"] == "hand"      # 2 steps: no success, and the arm follows the plan
    assert all(r["worst_multistart_m"] is None for r in reach.values())     # only a straying side's


def test_dry_run_tells_an_out_of_reach_pose():
    """ball_box_loading on the IIWA7: the near-table poses lie inside the arm's folded elbow (shoulder to
    wrist at least 0.40 m) from its mount; no joint seed reaches them."""
    reach = plan_reach("ball_box_loading", "iiwa7_sharpa")
    assert stray_sides(reach) == ["left", "right"]
    for r in reach.values():    # the left's worst: the tennis ball's pinch, turned 30 degrees (0.45 m out)
        assert r["worst_multistart_m"] > 0.1 and r["worst_target_from_base_m"][1] < 0.46


def test_dry_run_aims_where_the_plan_leaves_the_target():
    """fruit_bowl_loading on its paper embodiment: the left hand carries apple_1 to the bowl the right hand
    has just dragged to the centre; the dry run looks for the bowl there, not where it lay (aimed there, the
    left arm "strayed" 21 cm, 190 steps off the path, while the recorded arm followed)."""
    reach = plan_reach("fruit_bowl_loading", "ur5_rh56dfx")
    assert stray_sides(reach) == [] and all(r["worst_m"] < 0.01 for r in reach.values())


def test_failure_causes():
    reach = {"left": {"worst_m": 0.08, "off_path_steps": 50}, "right": {"worst_m": 0.08, "off_path_steps": 5}}
    assert stray_sides(reach) == ["left"]
    base = {"majority": False, "errors": [], "arm_strays": ["left"]}
    assert failure_cause(base) == "arm" and failure_cause({**base, "arm_strays": []}) == "hand"
    assert failure_cause({**base, "errors": ["seed 0: boom"]}) == "error"
    assert failure_cause({**base, "majority": True}) is None


def test_cli_embodiment_option():
    result = CliRunner().invoke(cli, ["bench", "demos", "--embodiment", OTHER, "--setting", TASK,
                                      "--episodes", "1", "--max-steps", "2"])
    assert result.exit_code == 0, result.output
    figures = json.loads(result.stdout)
    assert figures["table"] == {TASK: {OTHER: "0/1"}} and figures["max_steps"] == 2
    assert figures["markdown"].splitlines()[2] == f"| {TASK} | 0/1 | 0 |"
    assert figures["stop_when_decided"] and not figures["cells"][0]["decided_early"]
    result = CliRunner().invoke(cli, ["bench", "demos", "--embodiment", OTHER, "--setting", TASK,
                                      "--episodes", "2", "--max-steps", "2", "--all-seeds"])
    assert result.exit_code == 0, result.output
    figures = json.loads(result.stdout)
    assert figures["table"] == {TASK: {OTHER: "0/2"}} and not figures["stop_when_decided"]
    result = CliRunner().invoke(cli, ["bench", "demos", "--embodiment", "ur5_nope"])
    assert result.exit_code == 2 and "valid embodiment names" in result.output
