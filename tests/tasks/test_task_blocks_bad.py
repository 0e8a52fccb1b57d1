"""Task-file blocks and flags of the wrong kind fail with the file and the field, not a Python error."""

import copy

import pytest

from sim.errors import SpecError
from sim.registry import catalog_path, load_yaml
from sim.tasks import parse_task

PATH = catalog_path("tasks", "citrus_plate_loading")
BASE = load_yaml(PATH)


@pytest.mark.parametrize("edit, field, words", [
    (lambda r: r.update(zones=["left"]), "zones", "a mapping of zone name"),
    (lambda r: r.update(points=[[0, 0, 0]]), "points", "a mapping of point name"),
    (lambda r: r.update(table=0.75), "table", "a mapping {height"),
    (lambda r: r.update(demo_plan={"hand": "left"}), "demo_plan", "a list of steps"),
    (lambda r: r.update(demo_plan=["lemon_1"]), "demo_plan[0]", "a mapping with exactly one of 'pick', 'drag'"),
    (lambda r: r.update(demo_plan=[{"hand": "left", "pick": "lemon_1", "drag": "plate"}]), "demo_plan[0]",
     "exactly one of 'pick', 'drag'"),
    (lambda r: r.update(zones={"strip": {"xy_min": [0.2, 0.0], "xy_max": [0.1, 0.1]}}), "zones.strip",
     "xy_min below xy_max"),
    (lambda r: r["objects"]["plate"].update(fixed_pose="no"), "objects.plate.fixed_pose", "true or false"),
])
def test_a_block_of_the_wrong_kind_is_named(edit, field, words):
    raw = copy.deepcopy(BASE)
    edit(raw)
    with pytest.raises(SpecError) as err:
        parse_task(raw, PATH)
    assert err.value.field == field and words in err.value.expected and str(PATH) in str(err.value)


def test_absent_optional_blocks_are_empty():
    raw = copy.deepcopy(BASE)
    for key in ("zones", "points", "table", "demo_plan"):
        raw[key] = None
    task = parse_task(raw, PATH)
    assert task.zones == {} and task.points == {} and task.demo_plan == [] and task.table.height == 0.75
