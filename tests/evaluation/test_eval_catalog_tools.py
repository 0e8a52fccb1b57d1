"""The catalog's tool annotations: which tasks have them, that they load and resolve to task objects."""

import copy

import pytest

from evaluation import EpisodeEvaluator
from sim.errors import SpecError
from sim.registry import catalog_path, load_yaml, names
from sim.tasks import load_task, parse_task, task_context

# the paper's catalog, where a held object is used on something else: strike, pour, ladle
TOOL_STAGES = {
    "screwdriver_box_hammer": {"block_struck": ["hammer"]},
    "frypan_stand_pour": {"soy_poured": ["soy_sauce"], "oil_poured": ["olive_oil"]},
    "soup_serving": {"two_scoops": ["ladle"]},
    "toilet_lid_cleaner_pour": {"cleaner_poured": ["cleaner"]},
    "fridge_wine_interhand_pour": {"wine_poured": ["wine_bottle"]},
}


@pytest.mark.parametrize("task", names("tasks"))
def test_tool_annotations_load_and_resolve_to_free_task_objects(task):
    spec = load_task(task)
    ev = EpisodeEvaluator(spec.metrics, task_context(spec), source=str(spec.source))
    allowed = ev.tools.allowed if ev.tools else {}
    assert allowed == TOOL_STAGES.get(task, {})
    for tools in allowed.values():
        for tool in tools:     # a tool is held only if it can be lifted
            assert tool in spec.objects and spec.objects[tool].base == "free" and not spec.objects[tool].links


def test_unknown_tool_in_a_task_file_names_the_file_and_field():
    path = catalog_path("tasks", "soup_serving", "task")
    raw = copy.deepcopy(load_yaml(path))
    stage = next(i for i, s in enumerate(raw["metrics"]["stages"]) if s["id"] == "two_scoops")
    raw["metrics"]["stages"][stage]["tools"] = ["spoon"]
    with pytest.raises(SpecError) as info:
        parse_task(raw, path)
    assert str(path) in str(info.value) and f"metrics.stages[{stage}].tools[0]" in str(info.value)
    assert "'spoon'" in str(info.value) and "ladle" in str(info.value)
