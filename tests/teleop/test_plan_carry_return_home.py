"""Plan step `carry`, field `return_home`: after letting go both hands part and go back to their home
poses (opt-in: without it a carry's keyframes are what they were); and cleaner_box_loading's plan
(the carry with return_home, then the soap) on a seed where the soap's pinch missed without it."""

import dataclasses

import numpy as np
import pytest

from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.scene.sample import demonstration_seed
from sim.tasks import load_task
from teleop.demos import OPERATORS
from teleop.plan_steps.carry import HOME_APART_M
from teleop.recorder import home, record_episode
from teleop.scripted_operator import ScriptedOperator

TASK, EMBODIMENT = "cleaner_box_loading", "xarm7_leap"
CARRY = {"hand": "both", "carry": "cleaner", "place": "wooden_box", "place_offset": [-0.07, -0.03, -0.12],
         "grasp_height": 0.08}
# the soap's pinch after a carry that left the right arm where it let go: 4 cm out of reach on
# seeds 4 and 6 (stream path); from home it is picked
SOAP_SEED = 6


def _plan(steps):
    task = load_task(TASK)
    return parse_plan("t.yaml", {"demo_plan": steps}, PlanScope(task.objects, task.zones, task.points))


def _frames(plan):
    scene = demonstration_scene(TASK, EMBODIMENT, 0)
    scene.task = dataclasses.replace(scene.task, demo_plan=_plan(plan))    # not load_task's cached one
    op = ScriptedOperator()
    op.reset(scene, home(scene))
    return op, {s: op.sides[s]["timeline"].frames for s in ("right", "left")}


@pytest.mark.parametrize("value", ["yes", 1, None])
def test_check_refuses_a_return_home_that_is_not_a_flag(value):
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.return_home"):
        _plan([{**CARRY, "return_home": value}])


def test_hands_part_then_go_home_and_the_carry_itself_is_unchanged():
    _, plain = _frames([CARRY, {"hand": "right", "pick": "soap", "place": "wooden_box", "after": [0]}])
    op, homed = _frames([{**CARRY, "return_home": True},
                         {"hand": "right", "pick": "soap", "place": "wooden_box", "after": [0]}])
    alone = _frames([CARRY])[1]
    for side in ("right", "left"):
        carry_frames = len(alone[side]) - 1        # without the closing return home
        # the carry's own keyframes are the same with and without the field
        for a, b in zip(plain[side][:carry_frames], homed[side][:carry_frames]):
            assert a.end_step == b.end_step and np.allclose(a.pos, b.pos) and np.allclose(a.quat, b.quat)
        parted, at_home = homed[side][carry_frames], homed[side][carry_frames + 1]
        released = homed[side][carry_frames - 1]
        out = parted.pos - released.pos
        assert np.isclose(np.linalg.norm(out), HOME_APART_M) and abs(out[2]) < 1e-12   # apart, level
        assert np.sign(out[0]) == (1.0 if side == "right" else -1.0)               # each to its own side
        pos0, quat0 = op.sides[side]["home"]
        assert np.allclose(at_home.pos, pos0) and np.allclose(at_home.quat, quat0)


def test_the_task_plan_loads_the_cleaner_and_then_the_soap():
    """cleaner_box_loading's own plan on the stream path, on a seed the soap was missed without
    return_home (b2d bench demos measures all 12)."""
    spec = load_task(TASK)
    assert spec.demo_plan[0].get("return_home") is True
    scene = demonstration_scene(spec, EMBODIMENT, SOAP_SEED)
    rec = record_episode(scene, OPERATORS["stream"](), f"{SOAP_SEED:04d}", demonstration_seed(TASK, SOAP_SEED))
    record = rec.extra["episode_record"]
    assert rec.success, f"final stages {record['stage_final']}, drop {record['drop']}"
    assert not record["drop"] and not record["high_speed"]
