"""Plan step `drag`: the check refuses bad optional fields (naming them); and a tall shoe box pulled low with a light hook (medicine_shoebox_pack)
reaches the centre zone upright."""

import numpy as np
import pytest
import yaml

from sim import physics
from sim.errors import SpecError
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample
from sim.tasks import load_task, parse_task
from teleop.recorder import EpisodeRecording
from plan_runs import home_and_plan

TASK, EMBODIMENT = "medicine_shoebox_pack", "panda_orca"
LOW_HOOK = {"hook_depth": 0.05, "pitch_deg": 60, "hook_closure": 0.3}   # below the tall box's tipping height
UPRIGHT_DEG = 25.0


def _task(tmp_path, **fields):
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    raw["demo_plan"] = [{"hand": "left", "drag": "shoe_box", "to_zone": "center", **fields}]
    return parse_task(raw, tmp_path / "box.yaml")


@pytest.mark.parametrize("field, value, expected", [
    ("place_offset", [0.1], r"\[dx, dy\]"), ("place_offset", "left", r"\[dx, dy\]"),
    ("hook_depth", 0.0, r"below the rim in \(0, 0.11"), ("hook_depth", 0.2, r"below the rim"),
    ("pitch_deg", 85, r"degrees in \[0, 80\]"), ("pitch_deg", "down", r"degrees"),
    ("hook_closure", 0.0, r"fraction"), ("hook_closure", 1.5, r"fraction")])
def test_drag_refuses_bad_optional_fields(tmp_path, field, value, expected):
    with pytest.raises(SpecError, match=rf"box.yaml: field 'demo_plan\[0\].{field}'.*{expected}"):
        _task(tmp_path, **{field: value})


def _timeline(tmp_path, **fields):
    task = _task(tmp_path, **fields)
    scene = build_scene(task, EMBODIMENT, demonstration_sample(task, 0))
    data, op = home_and_plan(scene)
    return scene, data, op


def test_a_low_light_hook_pulls_the_tall_box_upright_into_the_zone(tmp_path):
    scene, data, op = _timeline(tmp_path, place_offset=[-0.045, 0.075], **LOW_HOOK)
    rec = EpisodeRecording(scene, data)
    body, worst = scene.object_body_ids["shoe_box"], 0.0
    for step in range(op.length):
        a = op.act(step, data)
        physics.step_control(scene.model, data, a)
        rec.step(data, a)
        worst = max(worst, np.degrees(np.arccos(np.clip(data.xmat[body][8], -1.0, 1.0))))
    assert worst < UPRIGHT_DEG
    assert rec.evaluator.latched["box_centered"]
