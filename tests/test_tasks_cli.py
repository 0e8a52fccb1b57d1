"""`b2d tasks show` prints a task's stage graph; `b2d list tasks` lists the 26 with their stages."""

import json

from click.testing import CliRunner

from b2d_cli.main import cli


def test_tasks_show_prints_the_stage_graph():
    result = CliRunner().invoke(cli, ["tasks", "show", "trash_disposal"])
    assert result.exit_code == 0, result.output
    out = result.output
    assert "[1] lid_open" in out and "[3] lid_closed  <- paper_in, bottle_in, peel_in" in out
    assert "{joint_open: {joint: trash_can/lid, threshold: 1.0}}" in out
    assert "terminal" in out and "{upright: {object: trash_can}}" in out
    graph = json.loads(CliRunner().invoke(cli, ["tasks", "show", "trash_disposal", "--json"]).output)
    assert [s["id"] for s in graph["stages"]][0] == "lid_open" and graph["joints"] == ["trash_can/lid"]


def test_tasks_show_unknown_task_lists_the_valid_ones():
    result = CliRunner().invoke(cli, ["tasks", "show", "juggling"])
    assert result.exit_code == 2 and "valid task names" in result.output and "soup_serving" in result.output


def test_list_tasks_shows_the_26_with_stages():
    rows = json.loads(CliRunner().invoke(cli, ["list", "tasks", "--json"]).output)
    assert len(rows) == 26 and all(r["stages"] for r in rows)


def test_tasks_check_reports_reach_and_rejects_unknown_names():
    result = CliRunner().invoke(cli, ["tasks", "check", "citrus_plate_loading", "--json"])
    assert result.exit_code == 0, result.output
    (entry,) = json.loads(result.output)
    assert entry["embodiment"] == "ur5_rh5dg2"
    assert {r["target"] for r in entry["targets"]} >= {"object lemon_1", "object orange_2"}
    assert all(r["arms"] for r in entry["targets"])
    result = CliRunner().invoke(cli, ["tasks", "check", "citrus_plate_loading", "--embodiment", "nope"])
    assert result.exit_code == 2 and "valid embodiment names" in result.output


def test_tasks_show_prints_stage_tools():
    graph = json.loads(CliRunner().invoke(cli, ["tasks", "show", "screwdriver_box_hammer", "--json"]).output)
    assert any(stage["tools"] for stage in graph["stages"])
    assert "tools:" in CliRunner().invoke(cli, ["tasks", "show", "screwdriver_box_hammer"]).output
