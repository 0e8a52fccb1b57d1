"""Invalid metrics specs fail at compile time, naming the file, the field path and what was expected."""

import pytest
from eval_synth import context

from evaluation import EpisodeEvaluator, TaskSpecError, compile_condition

OK_STAGE = {"upright": {"object": "box"}}


def spec_with(stages=None, terminal=None, **extra):
    return {"terminal": terminal or {"upright": {"object": "box"}}, "stages": stages or [], **extra}


def compile_error(spec, source="sim/catalog/tasks/demo.yaml") -> TaskSpecError:
    with pytest.raises(TaskSpecError) as info:
        EpisodeEvaluator(spec, context(), source=source)
    assert isinstance(info.value, ValueError)
    return info.value


def test_unknown_object_names_the_field_path_and_the_valid_names():
    stages = [{"id": "a", "predicate": OK_STAGE}, {"id": "b", "predicate": OK_STAGE},
              {"id": "c", "predicate": {"inside": {"object": "apple", "container": "crate"}}}]
    err = compile_error(spec_with(stages))
    assert err.field == "metrics.stages[2].predicate.inside.container"
    assert str(err).startswith("sim/catalog/tasks/demo.yaml: metrics.stages[2].predicate.inside.container")
    assert "'crate'" in str(err) and "box" in str(err) and "apple" in str(err)


def test_container_without_cavity_lists_containers():
    err = compile_error(spec_with(terminal={"inside": {"object": "apple", "container": "plate"}}))
    assert err.field == "metrics.terminal.inside.container"
    assert "interior_half_extents" in str(err) and "box" in str(err) and "fridge" in str(err)


def test_unknown_predicate_lists_predicates():
    err = compile_error(spec_with(terminal={"all": [OK_STAGE, {"levitating": {"object": "box"}}]}))
    assert err.field == "metrics.terminal.all[1].levitating"
    assert "upright" in str(err) and "struck_once" in str(err)


@pytest.mark.parametrize("cond,field,needle", [
    ({"upright": {}}, "metrics.terminal.upright.object", "required"),
    ({"upright": {"object": "box", "max_tilt": 5}}, "metrics.terminal.upright.max_tilt", "max_tilt_deg"),
    ({"upright": {"object": "box", "max_tilt_deg": "five"}}, "metrics.terminal.upright.max_tilt_deg", "number"),
    ({"within_distance": {"object": "box", "target": "nowhere", "max_dist": 1}},
     "metrics.terminal.within_distance.target", "seat_a"),
    ({"in_zone": {"object": "box", "zone": "moon"}}, "metrics.terminal.in_zone.zone", "center"),
    ({"joint_open": {"joint": "door", "threshold": 1}}, "metrics.terminal.joint_open.joint", "object/joint"),
    ({"within_distance": {"object": "box", "target": "apple", "max_dist": 1, "axes": "xz"}},
     "metrics.terminal.within_distance.axes", "xyz"),
    ({"at_rest": {"objects": []}}, "metrics.terminal.at_rest.objects", "non-empty"),
    ({"at_rest": {"objects": ["box", "ghost"]}}, "metrics.terminal.at_rest.objects[1]", "apple"),
    ({"all": []}, "metrics.terminal.all", "non-empty"),
    ({"upright": {"object": "box"}, "lifted": {"object": "box"}}, "metrics.terminal", "one key"),
    ({"stage": "nope"}, "metrics.terminal.stage", "stage id"),
    ({"sequence": {"steps": [{"bogus": {}}]}}, "metrics.terminal.sequence.steps[0].bogus", "predicate"),
    ({"inside": {"object": "apple", "container": "fridge", "box": {"half_extents": [1, 1]}}},
     "metrics.terminal.inside.box.half_extents", "3 finite numbers"),
])
def test_argument_errors(cond, field, needle):
    err = compile_error(spec_with(terminal=cond))
    assert err.field == field
    assert needle in str(err)


def test_dependency_cycle_is_rejected():
    stages = [{"id": "a", "predicate": OK_STAGE, "depends_on": ["c"]},
              {"id": "b", "predicate": OK_STAGE, "depends_on": ["a"]},
              {"id": "c", "predicate": OK_STAGE, "depends_on": ["b"]}]
    err = compile_error(spec_with(stages))
    assert err.field == "metrics.stages[0].depends_on"
    assert "acyclic" in str(err) and "a -> c -> b -> a" in str(err)


def test_unknown_and_self_dependencies_are_rejected():
    err = compile_error(spec_with([{"id": "a", "predicate": OK_STAGE, "depends_on": ["zzz"]}]))
    assert err.field == "metrics.stages[0].depends_on[0]"
    err = compile_error(spec_with([{"id": "a", "predicate": OK_STAGE, "depends_on": ["a"]}]))
    assert err.field == "metrics.stages[0].depends_on[0]"


def test_stage_reference_cycle_and_latched_inside_stage_are_rejected():
    stages = [{"id": "a", "predicate": {"stage": "b"}}, {"id": "b", "predicate": {"not": {"stage": "a"}}}]
    assert "a -> b -> a" in str(compile_error(spec_with(stages)))
    err = compile_error(spec_with([{"id": "a", "predicate": OK_STAGE},
                                   {"id": "b", "predicate": {"latched": "a"}}]))
    assert err.field == "metrics.stages[1].predicate.latched"


@pytest.mark.parametrize("spec,field", [
    ({"stages": []}, "metrics.terminal"),
    ({**spec_with(), "dwel_s": 0.5}, "metrics.dwel_s"),
    ({**spec_with(), "dwell_s": -1}, "metrics.dwell_s"),
    ({**spec_with(), "expert_horizon_steps": 0}, "metrics.expert_horizon_steps"),
    (spec_with([{"id": "a", "predicate": OK_STAGE}, {"id": "a", "predicate": OK_STAGE}]), "metrics.stages[1].id"),
    (spec_with([{"id": "a"}]), "metrics.stages[0].predicate"),
    (spec_with([{"id": "a", "predicate": OK_STAGE, "depend_on": []}]), "metrics.stages[0].depend_on"),
    ({**spec_with(), "safety": {"drop": {"objects": ["ghost"]}}}, "metrics.safety.drop.objects[0]"),
    ({**spec_with(), "safety": {"collisions": {}}}, "metrics.safety.collisions"),
    ({**spec_with(), "grasp": {"objects": ["box"], "sigma_v": 0}}, "metrics.grasp.sigma_v"),
])
def test_spec_level_errors(spec, field):
    assert compile_error(spec).field == field


def test_compile_condition_field_prefix_and_no_source():
    with pytest.raises(TaskSpecError, match=r"^success\.upright\.object: expected an object"):
        compile_condition({"upright": {"object": "car"}}, context(), field="success")
