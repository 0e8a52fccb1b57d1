"""Plan step `pour`, field `tilt_toward`: the check refuses what is not a direction on the table top,
naming the field; the tipped keyframe turns the mouth the way it says (either way, from the same
grasp); and toilet_lid_cleaner_pour's plan (lid opened, the cleaner held from the side and tipped
towards the bowl, lid pushed shut) reaches stable success on the stream path on one seed (b2d bench
demos measures all 12)."""

import dataclasses

import mujoco
import numpy as np
import pytest

from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from sim.scene.builder import build_scene, demonstration_scene
from sim.scene.sample import demonstration_sample, demonstration_seed
from sim.tasks import load_task
from teleop.demos import DEFAULT_OPERATOR, OPERATORS
from teleop.recorder import record_episode
from plan_runs import home_and_plan

TASK, EMBODIMENT = "toilet_lid_cleaner_pour", "xarm7_leap"
POUR = {"hand": "left", "pour": "cleaner", "into": "bowl_left", "grasp": "side"}
SEED = 1        # a demonstration episode that succeeded when the plan landed


def _plan(steps):
    task = load_task(TASK)
    return parse_plan("t.yaml", {"demo_plan": steps}, PlanScope(task.objects, task.zones, task.points))


@pytest.mark.parametrize("value", [[1.0], [1.0, 0.0, 0.0], "right", [0.0, 0.0], [True, 0.0]])
def test_check_refuses_a_tilt_toward_that_is_no_direction(value):
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.tilt_toward"):
        _plan([{**POUR, "tilt_toward": value}])


def _tipped_mouth_x(toward) -> float:
    """x of the cleaner's mouth axis in the most tipped keyframe of a pour planned with ``toward``."""
    scene = demonstration_scene(TASK, EMBODIMENT, 0)
    scene.task = dataclasses.replace(scene.task, demo_plan=_plan([{**POUR, "tilt_toward": toward}]))
    data, op = home_and_plan(scene)
    frames = op.sides["left"]["timeline"].frames
    body = scene.object_body_ids["cleaner"]

    def rot(frame):
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, frame.quat)
        return R.reshape(3, 3)

    in_hand = rot(frames[2]).T @ data.xmat[body].reshape(3, 3)       # descended, about to close
    mouths = [rot(f) @ in_hand @ np.array([0.0, 0.0, 1.0]) for f in frames[3:-1]]   # held
    tipped = min(mouths, key=lambda m: m[2])
    assert tipped[2] < np.cos(np.radians(60.0))
    return float(tipped[0])


def test_the_mouth_tips_the_way_tilt_toward_says():
    assert _tipped_mouth_x([1.0, 0.0]) > 0.9
    assert _tipped_mouth_x([-1.0, 0.0]) < -0.9


def test_the_task_plan_opens_pours_and_closes():
    spec = load_task(TASK)
    assert any(step.get("tilt_toward") for step in spec.demo_plan)
    seed = demonstration_seed(TASK, SEED)
    scene = build_scene(spec, EMBODIMENT, demonstration_sample(spec, seed))
    rec = record_episode(scene, OPERATORS[DEFAULT_OPERATOR](), f"{SEED:04d}", seed)
    record = rec.extra["episode_record"]
    assert rec.success, f"final stages {record['stage_final']}, drop {record['drop']}"
    assert record["termination"] == "stable_success" and all(record["stage_latched"])
    assert not record["drop"] and not record["high_speed"]
