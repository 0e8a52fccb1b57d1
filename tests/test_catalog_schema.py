"""Every kind of catalog file goes through one schema layer (sim/schema): an unknown key, a value of the
wrong type and an out-of-range value are refused by the real loader, and the message names the file and
the field. Each case edits a copy of a real catalog file in a temporary folder."""

import copy
import re

import pytest
import yaml

from catalog_files import edited_catalog_file
from policies.config import CONFIG_ROOT, load_policy_config
from sim import registry
from sim.embodiment import description
from sim.errors import SpecError
from sim.tasks import parse_task

CATALOG = registry.CATALOG


def _write(tmp_path, source, edit, name=None):
    raw = yaml.safe_load(source.read_text())
    edit(raw)
    path = tmp_path / (name or source.name)
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    return path


def _profile(tmp_path, edit):
    path = _write(tmp_path, CATALOG / "sensor_profiles" / "preview.yaml", edit)
    return path, lambda: registry.parse_sensor_profile(registry.load_yaml(path), path)


def _channel(tmp_path, edit):
    path = _write(tmp_path, CATALOG / "channels" / "inv_equi.yaml", edit)
    return path, lambda: registry.read_channel(path)


def _settings(tmp_path, edit):
    path = _write(tmp_path, CATALOG / "settings.yaml", edit)
    return path, lambda: registry.read_settings(path)


def _task(tmp_path, edit):
    path = _write(tmp_path, CATALOG / "tasks" / "trash_disposal.yaml", edit)
    return path, lambda: parse_task(registry.load_yaml(path), path)


def _hand(tmp_path, edit):
    path = _write(tmp_path, CATALOG / "hands" / "allegro.yaml", edit)
    return path, lambda: description.read_hand_file(path)


def _policy(tmp_path, edit):
    path = _write(tmp_path, CONFIG_ROOT / "act" / "tiny.yaml", edit)
    return path, lambda: load_policy_config("act", str(path))


def _first_link(raw):
    return raw["fingers"][0]["links"][0]


FILE_CASES = {
    "sensor profile": (_profile, [
        ("unknown key", lambda r: r["cameras"].update(fov=60), "cameras.fov", "unknown key 'fov'"),
        ("wrong type", lambda r: r.update(rate_hz="20"), "rate_hz", "an integer"),
        ("out of range", lambda r: r.update(rate_hz=1000), "rate_hz", "an integer in [1, 60]"),
        ("rate not dividing the control rate", lambda r: r.update(rate_hz=7), "rate_hz", "dividing the control rate"),
        ("duplicate camera", lambda r: r["cameras"].update(ids=["chest", "overhead", "chest"]), "cameras.ids",
         "listed once each (repeated: ['chest'])"),
        ("unknown camera", lambda r: r["cameras"].update(ids=["chest", "nose"]), "cameras.ids[1]", "'overhead'"),
        ("tactile step out of range", lambda r: r["tactile"].update(step=0), "tactile.step", "an integer > 0"),
    ]),
    "channel": (_channel, [
        ("unknown key", lambda r: r.update(resample_lighting=True), "resample_lighting", "unknown key"),
        ("wrong type", lambda r: r.update(anchored="yes"), "anchored", "true or false"),
        ("out of range", lambda r: r.update(paper_name=""), "paper_name", "a non-empty string"),
    ]),
    "settings": (_settings, [
        ("unknown key", lambda r: r["paper_settings"][2].update(seed=1), "paper_settings[2].seed", "unknown key"),
        ("wrong type", lambda r: r["paper_settings"][0].update(available="no"), "paper_settings[0].available",
         "true or false"),
        ("out of range", lambda r: r.update(paper_settings=[]), "paper_settings", "at least 1 item"),
    ]),
    "task": (_task, [
        ("unknown key", lambda r: r.update(difficulty="hard"), "difficulty", "unknown key 'difficulty'"),
        ("unknown object key", lambda r: r["objects"]["paper"].update(colour=[1, 0, 0, 1]), "objects.paper.colour",
         "an object key from"),
        ("wrong type", lambda r: r["objects"]["paper"].update(friction="high"), "objects.paper.friction",
         "a number in [0.05, 2.0]"),
        ("out of range", lambda r: r["table"].update(thickness=0.5), "table.thickness", "a number in [0.01, 0.2] m"),
        ("rgba out of range", lambda r: r["objects"]["paper"].update(rgba=[1, 0, 0, 3]), "objects.paper.rgba[3]",
         "a number in [0, 1]"),
    ]),
    "hand": (_hand, [
        ("unknown key", lambda r: _first_link(r).update(colour="red"), "fingers[0].links[0].colour", "unknown key"),
        ("wrong type", lambda r: r["actuators"][0].update(effort="strong"), "actuators[0].effort", "a number > 0"),
        ("out of range", lambda r: _first_link(r).update(mass=0), "fingers[0].links[0].mass",
         "a number in (0, 100.0] kg"),
        ("condim out of range", lambda r: r.update(geom_defaults={"condim": 5}), "geom_defaults.condim", "one of 1"),
        ("link too heavy", lambda r: _first_link(r).update(mass=500.0), "fingers[0].links[0].mass",
         "a number in (0, 100.0] kg"),
        ("retarget wrong type", lambda r: r["retarget"]["fingertips"][0].update(pos=[0, "12", 0]),
         "retarget.fingertips[0].pos[1]", "a number in [-10.0, 10.0] m"),
    ]),
    "policy config": (_policy, [
        ("unknown key", lambda r: r["train"].update(momentum=0.9), "train.momentum", "unknown key 'momentum'"),
        ("wrong type", lambda r: r["train"].update(steps="many"), "train.steps", "an integer"),
        ("out of range", lambda r: r["action"].update(horizon=0), "action.horizon", "an integer in [1, 256]"),
    ]),
}


@pytest.mark.parametrize("kind, case", [(k, c) for k, (_, cases) in FILE_CASES.items() for c in cases],
                         ids=lambda v: v if isinstance(v, str) else v[0])
def test_a_bad_catalog_file_is_refused_naming_file_and_field(tmp_path, kind, case):
    _, edit, field, words = case
    path, load = FILE_CASES[kind][0](tmp_path, edit)
    with pytest.raises(SpecError) as err:
        load()
    message = str(err.value)
    assert message.startswith(f"{path}: field '{field}': expected "), message
    assert words in message, message


# arms and embodiments are read from their catalog folder by name: the edited copy replaces the folder
FOLDER_CASES = [
    ("arms", "ur5", "load_arm", "unknown key", lambda r: r.update(payload_kg=5), "payload_kg", "unknown key"),
    ("arms", "ur5", "load_arm", "wrong type", lambda r: r["chain"][0].update(range="wide"), "chain[0].range",
     "a list"),
    ("arms", "ur5", "load_arm", "out of range", lambda r: r["reach"].update(home_radius_m=-0.1),
     "reach.home_radius_m", "a number in (0, 10.0] m"),
    ("arms", "ur5", "load_arm", "joint range beyond a turn", lambda r: r["chain"][1].update(range=[-1e9, 1.0]),
     "chain[1].range[0]", "a number in [-6.3, 6.3] rad"),
    ("arms", "ur5", "load_arm", "seed of the wrong length", lambda r: r.update(home_seed=[0.0, 1.0]),
     "home_seed.left", "a list of 6 numbers"),
    ("embodiments", "ur5_shadow", "load_embodiment", "unknown key", lambda r: r.update(payload=3), "payload",
     "unknown key 'payload'"),
    ("embodiments", "ur5_shadow", "load_embodiment", "wrong type", lambda r: r["home"]["right_wrist"].update(xyz="up"),
     "home.right_wrist.xyz", "a list"),
    ("embodiments", "ur5_shadow", "load_embodiment", "out of range",
     lambda r: r.setdefault("cameras", {}).update(chest={"fovy": 200}), "cameras.chest.fovy", "a number in (0, 180)"),
    ("embodiments", "ur5_shadow", "load_embodiment", "unknown camera",
     lambda r: r.setdefault("cameras", {}).update(nose={"fovy": 60}), "cameras.nose", "'chest'"),
]


@pytest.mark.parametrize("kind, name, loader, what, edit, field, words", FOLDER_CASES,
                         ids=[f"{c[0]}-{c[3]}" for c in FOLDER_CASES])
def test_a_bad_arm_or_embodiment_file_is_refused_naming_file_and_field(tmp_path, monkeypatch, kind, name, loader,
                                                                        what, edit, field, words):
    with edited_catalog_file(monkeypatch, tmp_path, kind, name, edit) as path:
        with pytest.raises(description.DescriptionError) as err:
            getattr(description, loader)(name)
    message = str(err.value)
    assert message.startswith(f"{path}: field '{field}': expected "), message
    assert words in message, message
    assert isinstance(err.value, SpecError)       # callers that catch SpecError catch these too


def test_every_finding_of_a_file_is_listed(tmp_path):
    def two_faults(raw):
        raw["cameras"]["width"] = -1
        raw["colour"] = "red"
    path, load = _profile(tmp_path, two_faults)
    with pytest.raises(SpecError) as err:
        load()
    lines = str(err.value).splitlines()
    assert len(lines) == 2 and str(path) in lines[0]
    assert {err.value.field, re.search(r"field '([^']+)'", lines[1])[1]} == {"cameras.width", "colour"}


def test_a_file_that_is_not_a_mapping_names_the_file(tmp_path):
    path = tmp_path / "list.yaml"
    path.write_text("- 1\n- 2\n")
    with pytest.raises(SpecError, match=rf"{re.escape(str(path))}: field '<document>': expected a YAML mapping"):
        registry.read_channel(path)


# The rendered data are keyed by these hashes: moving the checks into the schema must not move them.
# Issue 22 gave paper (tessellation [16, 8]) and preview ([8, 4]) a primitive tessellation: new hashes.
PROFILE_HASHES = {"paper": "e1a2ce6e3866", "policy_paper": "54c0b56eda1d", "policy_tiny": "f5ed4c7b2795",
                  "preview": "89f20390f5fd"}


def test_the_catalog_profiles_keep_their_content_hashes():
    assert {n: registry.sensor_profile(n).content_hash for n in registry.names("sensor_profiles")} == PROFILE_HASHES


def test_a_valid_file_loads_unchanged_through_the_schema(tmp_path):
    """A profile built in code (policies/observe.py does) still goes through: defaults filled, raw kept."""
    raw = {"name": "policy_inputs", "rate_hz": 20, "cameras": {"ids": ["chest"], "width": 64, "height": 48,
                                                               "modalities": ["rgb"]}}
    profile = registry.parse_sensor_profile(copy.deepcopy(raw))
    assert profile.raw == raw and profile.tactile_enabled is False and profile.clip_far_m == 5.0
    assert profile.occupancy_voxel_size_m == 0.02 and profile.tessellation is None
