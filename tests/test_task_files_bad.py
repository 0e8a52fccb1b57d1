"""Bad task files fail to load with the file, the field and what was expected."""

import copy

import pytest
import yaml

from sim.errors import SpecError
from sim.registry import catalog_path, load_yaml
from sim.tasks import parse_task

BASE = load_yaml(catalog_path("tasks", "trash_disposal"))


def _load(tmp_path, mutate):
    raw = copy.deepcopy(BASE)
    mutate(raw)
    path = tmp_path / "bad_task.yaml"
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    with pytest.raises(SpecError) as err:
        parse_task(load_yaml(path), path)
    assert str(path) in str(err.value)
    return err.value


def _stage(raw, i):
    return raw["metrics"]["stages"][i]


def test_unknown_predicate(tmp_path):
    err = _load(tmp_path, lambda r: _stage(r, 1).update(predicate={"levitating": {"object": "paper"}}))
    assert err.field == "metrics.stages[1].predicate.levitating"
    assert "predicate" in err.expected and "inside" in err.expected and "joint_open" in err.expected


def test_cycle_in_the_stage_graph(tmp_path):
    def cycle(raw):
        _stage(raw, 0)["depends_on"] = ["lid_closed"]      # lid_closed already depends on lid_open (via paper_in)
    err = _load(tmp_path, cycle)
    assert err.field.startswith("metrics.stages[") and err.field.endswith("].depends_on")
    assert "acyclic" in err.expected and "lid_open" in str(err)


def test_reference_to_a_missing_object(tmp_path):
    err = _load(tmp_path, lambda r: _stage(r, 1).update(
        predicate={"inside": {"object": "newspaper", "container": "trash_can"}}))
    assert err.field == "metrics.stages[1].predicate.inside.object"
    assert "paper" in err.expected and "banana_peel" in err.expected


def test_reference_to_a_missing_joint_lists_the_joints(tmp_path):
    err = _load(tmp_path, lambda r: _stage(r, 0).update(
        predicate={"joint_open": {"joint": "trash_can/door", "threshold": 1.0}}))
    assert err.field == "metrics.stages[0].predicate.joint_open.joint" and "trash_can/lid" in err.expected


def test_missing_object_in_the_terminal_and_the_safety_rules(tmp_path):
    err = _load(tmp_path, lambda r: r["metrics"]["terminal"]["all"].append({"upright": {"object": "bin"}}))
    assert err.field == "metrics.terminal.all[5].upright.object"
    err = _load(tmp_path, lambda r: r["metrics"]["safety"]["drop"]["objects"].append("bin"))
    assert err.field == "metrics.safety.drop.objects[4]"


def test_support_must_be_an_earlier_object(tmp_path):
    err = _load(tmp_path, lambda r: r["objects"]["paper"].update(pose={"support": "shelf", "xy": [0, 0]}))
    assert err.field == "objects.paper.pose.support" and "trash_can" in err.expected


def test_parts_must_be_centred_on_the_object_frame(tmp_path):
    err = _load(tmp_path, lambda r: r["objects"]["bottle"]["parts"][0].update(pos=[0, 0, 0.05]))
    assert err.field == "objects.bottle.parts" and "centred" in err.expected


@pytest.mark.parametrize("mutate,field,expected", [
    (lambda r: r["objects"]["trash_can"]["parts"][0]["open_cylinder"].update(wall=0.2),
     "objects.trash_can.parts[0].open_cylinder.wall", "less than half"),
    (lambda r: r["objects"]["trash_can"]["parts"].append({"shape": "cone", "size": [0.1]}),
     "objects.trash_can.parts[1].shape", "one of"),
    (lambda r: r["objects"]["trash_can"]["links"]["lid"]["joint"].update(range=[1.0, 0.0]),
     "objects.trash_can.links.lid.joint.range", "low < high"),
    (lambda r: r["objects"]["trash_can"]["links"]["lid"]["joint"].update(initial=2.5),
     "objects.trash_can.links.lid.joint.initial", "within the range"),
    (lambda r: r["objects"]["trash_can"]["links"]["lid"]["joint"].update(type="ball"),
     "objects.trash_can.links.lid.joint.type", "hinge"),
    (lambda r: r["objects"]["trash_can"]["parts"].append({"shape": "box", "size": [0.1, 0.1]}),
     "objects.trash_can.parts[1].size", "3 positive half sizes for a box"),
    (lambda r: r["objects"]["trash_can"]["parts"].append({"shape": "box", "size": [0.1, 0.1, 0.1], "colour": 1}),
     "objects.trash_can.parts[1].colour", "a part key from"),
    (lambda r: r["objects"]["trash_can"]["parts"].append({"mesh": "lid.obj", "size": [0.1, 0.1, 0.1]}),
     "objects.trash_can.parts[1]", "exactly one of shape (with size"),
    (lambda r: r["objects"]["trash_can"]["parts"][0]["open_cylinder"].update(segments=3),
     "objects.trash_can.parts[0].open_cylinder.segments", "an integer >= 6"),
    (lambda r: r["objects"]["trash_can"]["links"]["lid"].pop("joint"), "objects.trash_can.links.lid.joint",
     "a value (field is missing)"),
    (lambda r: r["objects"]["trash_can"]["links"]["lid"]["joint"].update(axis=[0, 0, 0]),
     "objects.trash_can.links.lid.joint.axis", "a non-zero axis"),
    (lambda r: r["objects"]["trash_can"]["links"].update({"lid/handle": r["objects"]["trash_can"]["links"]["lid"]}),
     "objects.trash_can", "have no '/' (['lid/handle'] do not)"),
    (lambda r: r["objects"]["trash_can"].update(base="glued"), "objects.trash_can.base", "free"),
    (lambda r: r["objects"]["paper"].update(colour=[1, 0, 0, 1]), "objects.paper.colour", "object key"),
])
def test_bad_geometry_and_joints(tmp_path, mutate, field, expected):
    err = _load(tmp_path, mutate)
    assert err.field == field and expected in err.expected


@pytest.mark.parametrize("mutate,field,expected", [
    (lambda r: r["objects"]["paper"].update(mass=0), "objects.paper.mass", "a number in [0.001, 100.0] kg"),
    (lambda r: r["objects"]["paper"].update(mass=-0.2), "objects.paper.mass", "a number in [0.001, 100.0] kg"),
    (lambda r: r["objects"]["paper"].update(mass=250.0), "objects.paper.mass", "a number in [0.001, 100.0] kg"),
    (lambda r: r["objects"]["paper"].update(mass="light"), "objects.paper.mass", "a number in"),
    (lambda r: r["objects"]["paper"].update(mass=float("nan")), "objects.paper.mass", "a number in"),
    (lambda r: r["objects"]["paper"].update(friction=0), "objects.paper.friction", "a number in [0.05, 2.0]"),
    (lambda r: r["objects"]["paper"].update(friction=-1.0), "objects.paper.friction", "a number in [0.05, 2.0]"),
    (lambda r: r["objects"]["paper"].update(friction=8.0), "objects.paper.friction", "a number in [0.05, 2.0]"),
    (lambda r: r["objects"]["paper"].update(rolling_friction=0.5), "objects.paper.rolling_friction",
     "a number in [0.0, 0.01] m"),
    (lambda r: (r["objects"]["paper"].pop("mass"), r["objects"]["paper"].update(density=2.0)),
     "objects.paper.density", "a number in [10.0, 25000.0] kg/m^3"),
    (lambda r: r["objects"]["trash_can"]["links"]["lid"].update(mass=0), "objects.trash_can.links.lid.mass",
     "a number in [0.001, 100.0] kg"),
    (lambda r: r["table"].update(friction=0.0), "table.friction", "a number in [0.05, 2.0]"),
    (lambda r: r["table"].update(height=3.0), "table.height", "a number in [0.4, 1.2] m"),
])
def test_mass_and_friction_are_range_checked(tmp_path, mutate, field, expected):
    err = _load(tmp_path, mutate)
    assert err.field == field and expected in err.expected, str(err)


def test_density_gives_the_mass_and_excludes_a_declared_mass(tmp_path):
    raw = copy.deepcopy(BASE)
    del raw["objects"]["paper"]["mass"]
    raw["objects"]["paper"]["density"] = 100.0
    path = tmp_path / "density.yaml"
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    paper = parse_task(load_yaml(path), path).objects["paper"]
    assert paper.mass == pytest.approx(100.0 * sum(p.volume for p in paper.parts))
    err = _load(tmp_path, lambda r: r["objects"]["paper"].update(density=100.0))
    assert err.field == "objects.paper" and "not both" in err.expected
