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
from teleop.scripted_operator import ScriptedOperator, hand_grasp

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
    raw = yaml.safe_load((description.HANDS_DIR / "rh5dg2.yaml").read_text())
    raw["tabletop_grasp"]["late"] = ["thumb_twist"]
    (tmp_path / "rh5dg2.yaml").write_text(yaml.safe_dump(raw))
    monkeypatch.setattr(description, "HANDS_DIR", tmp_path)
    description.load_hand.cache_clear()
    try:
        with pytest.raises(ValueError, match=r"rh5dg2.yaml: field 'tabletop_grasp.late': 'thumb_twist'"):
            description.load_hand("rh5dg2")
    finally:
        description.load_hand.cache_clear()


def test_negative_rolling_friction_is_refused(tmp_path):
    task = load_task("citrus_plate_loading")
    raw = yaml.safe_load(task.source.read_text())
    raw["objects"]["lemon_1"]["rolling_friction"] = -0.1
    with pytest.raises(SpecError, match="objects.lemon_1.rolling_friction"):
        parse_task(raw, tmp_path / "citrus.yaml")
