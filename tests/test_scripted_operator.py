"""The scripted operator on the paper's setting: it really grasps, carries and places fruit."""

import numpy as np
import pytest
import yaml

from sim.embodiment import description
from sim.errors import SpecError
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample
from sim.tasks import load_task, parse_task
from teleop.recorder import record_episode
from teleop.plan_steps.pick_place import place_offset
from teleop.scripted_operator import ScriptedOperator, hand_grasp

from catalog_files import edited_catalog_file

SEED = 2      # a demonstration sample in which all four fruit stay on the plate


@pytest.fixture(scope="module")
def recording():
    task = load_task("citrus_plate_loading")
    scene = build_scene(task, "ur5_rh5dg2", demonstration_sample(task, SEED))
    return record_episode(scene, ScriptedOperator(), "op", SEED)


def test_fruit_is_lifted_and_placed(recording):
    lemon = recording.object_names.index("lemon_1")
    z = recording.object_pose[:, lemon, 2]
    assert z.max() - z[0] > 0.10, "lemon_1 was never lifted 10 cm"
    latched = recording.stage_latched[-1]
    assert latched.sum() >= 3, f"only stages {np.flatnonzero(latched)} latched"
    assert recording.extra["lscr"] >= 0.75


def test_episode_reaches_stable_success(recording):
    """All four fruit on the plate and at rest for the dwell time: reach-and-stop ends it early."""
    record = recording.extra["episode_record"]
    assert recording.success, f"final stages {record['stage_final']}, drop {record['drop']}"
    assert record["termination"] != "horizon" and record["steps_to_stable"] is not None
    assert not record["drop"] and not record["high_speed"]


def test_left_grasp_mirrors_right():
    hand = description.load_embodiment("ur5_rh5dg2").hand
    right, left = hand_grasp(hand, "right"), hand_grasp(hand, "left")
    assert np.allclose(left.centre, right.centre * [-1, 1, 1])
    assert right.late == ("thumb_yaw", "thumb_flex")


def test_tabletop_grasp_with_unknown_actuator_names_file_and_field(tmp_path, monkeypatch):
    def late_thumb_twist(raw):
        raw["tabletop_grasp"]["late"] = ["thumb_twist"]

    with edited_catalog_file(monkeypatch, tmp_path, "hands", "rh5dg2", late_thumb_twist):
        with pytest.raises(ValueError, match=r"rh5dg2.yaml: field 'tabletop_grasp.late': 'thumb_twist'"):
            description.load_hand("rh5dg2")


def test_negative_rolling_friction_is_refused(tmp_path):
    task = load_task("citrus_plate_loading")
    raw = yaml.safe_load(task.source.read_text())
    raw["objects"]["lemon_1"]["rolling_friction"] = -0.1
    with pytest.raises(SpecError, match="objects.lemon_1.rolling_friction"):
        parse_task(raw, tmp_path / "citrus.yaml")


@pytest.mark.parametrize("bad", [[0.1], [0.0, 0.0, 0.0, 0.0], "near", [0.0, float("nan")]])
def test_bad_place_offset_names_file_and_field(tmp_path, bad):
    raw = yaml.safe_load(load_task("citrus_plate_loading").source.read_text())
    raw["demo_plan"][1]["place_offset"] = bad
    with pytest.raises(SpecError, match=r"citrus.yaml: field 'demo_plan\[1\].place_offset'"):
        parse_task(raw, tmp_path / "citrus.yaml")


def test_place_offset_dz_defaults_to_the_targets_top():
    assert place_offset({"place_offset": [0.065, -0.055]}).tolist() == [0.065, -0.055, 0.0]
    assert place_offset({"place_offset": [0.065, -0.07, 0.02]}).tolist() == [0.065, -0.07, 0.02]


def _operator_with_lemon_at(offset_from_hand):
    """The operator planned on seed SEED's scene, with lemon_1 put `offset_from_hand` away from where
    the plan expects it in the right hand at the first above-the-target check."""
    import mujoco

    task = load_task("citrus_plate_loading")
    scene = build_scene(task, "ur5_rh5dg2", demonstration_sample(task, SEED))
    data = scene.home_data()
    op = ScriptedOperator()
    op.reset(scene, data)
    side = op.sides["right"]
    carried_at, name, planned_offset, _ = side["corrections"][0]
    adr = scene.model.jnt_qposadr[scene.model.body_jntadr[scene.object_body_ids[name]]]
    data.qpos[adr:adr + 3] = data.site_xpos[side["wrist_site_id"]] + planned_offset + offset_from_hand
    mujoco.mj_forward(scene.model, data)
    before = [f.pos.copy() for f in side["timeline"].frames]
    op._correct_place(side, data, carried_at)
    return before, [f.pos for f in side["timeline"].frames]


def test_a_slipped_object_shifts_the_lowering():
    """The lemon sits 2 cm further right in the hand: the hand lowers 2 cm further left."""
    before, after = _operator_with_lemon_at(np.array([0.02, -0.01, 0.0]))
    shifts = {tuple(np.round(a - b, 6)) for a, b in zip(after, before)}
    assert shifts == {(0.0, 0.0, 0.0), (-0.02, 0.01, 0.0)}


def test_an_object_not_in_the_hand_changes_nothing():
    before, after = _operator_with_lemon_at(np.array([0.3, 0.0, 0.0]))
    assert all(np.array_equal(a, b) for a, b in zip(after, before))
