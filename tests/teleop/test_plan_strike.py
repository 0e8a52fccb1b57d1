"""Plan step `strike`: its load-time check, its swing and a real episode striking a block once."""

import dataclasses

import numpy as np
import pytest

from sim import physics
from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task
from teleop.plan_steps.strike import STRIKE_FOLLOW_M, STRIKE_RISE_M, swing_steps
from teleop.recorder import EpisodeRecording
from plan_runs import home_and_plan

TASK, EMBODIMENT = "screwdriver_box_hammer", "ur5_rh56dfx"
# a screwdriver pinched by the RH56DFX strikes with its handle's butt (the task's hammer, lifted only by a flat
# pinch: tests/teleop/test_plan_strike_flat_pinch.py)
STEP = {"hand": "left", "strike": "wood_block", "tool": "screwdriver_left", "strike_point": [-0.085, 0.0, 0.0],
        "place": "table", "place_offset": [-0.35, -0.05], "grasp": "pinch", "grasp_yaw": "across"}
MIN_SPEED_M_S = 0.8             # the task's struck_once


def _check(**fields):
    task = load_task(TASK)
    return parse_plan("t.yaml", {"demo_plan": [{**STEP, **fields}]}, PlanScope(task.objects, task.zones, task.points))


@pytest.mark.parametrize("fields, field", [
    ({"strike": "anvil"}, "strike"),
    ({"tool": "wood_block"}, "tool"),                 # the target itself
    ({"strike_point": [0.3, 0.0, 0.0]}, "strike_point"),   # off the 18 cm screwdriver
    ({"strike_point": [0.0, 0.0]}, "strike_point"),
    ({"place": "screwdriver_left"}, "place"),         # onto itself
    ({"place_offset": [0.1]}, "place_offset"),
    ({"grasp": "hook"}, "grasp"),
    ({"grasp": "side"}, "grasp"),                      # a side grasp is pick's and pour's
    ({"grasp_yaw": 270}, "grasp_yaw"),
    ({"approach_pitch_deg": 95}, "approach_pitch_deg"),
    ({"times": 2}, "times"),
])
def test_check_refuses_bad_fields(fields, field):
    with pytest.raises(SpecError, match=rf"demo_plan\[0\]\.{field}"):
        _check(**fields)


def test_check_accepts_a_strike():
    assert _check()[0]["strike"] == "wood_block"
    assert _check(grasp="power", grasp_point=[-0.045, 0.0, 0.0], place="box")[0]["tool"] == "screwdriver_left"


def _scene(before=()):
    """The task's scene with only the strike (after the steps ``before``): the evaluator its struck_once."""
    spec = load_task(TASK)
    stage = next(s for s in spec.metrics["stages"] if s["id"] == "block_struck")
    struck = {**stage["predicate"]["struck_once"], "tool": STEP["tool"], "head_offset": STEP["strike_point"]}
    metrics = {**spec.metrics, "stages": [{"id": "block_struck", "predicate": {"struck_once": struck}}],
               "terminal": {"latched": "block_struck"}}
    plan = parse_plan("t.yaml", {"demo_plan": [*before, {**STEP, "after": list(range(len(before)))}]},
                      PlanScope(spec.objects, spec.zones, spec.points))
    spec = dataclasses.replace(spec, metrics=metrics, demo_plan=plan)
    scene = demonstration_scene(spec, EMBODIMENT)
    data, op = home_and_plan(scene)
    return scene, data, op


def _swing(frames):
    """Index of the swing's keyframe: straight down by rise + follow-through."""
    down = STRIKE_RISE_M + STRIKE_FOLLOW_M
    return next(i for i in range(1, len(frames))
                if np.allclose(frames[i - 1].pos - frames[i].pos, [0.0, 0.0, down], atol=1e-9))


def test_swing_is_fast_enough_and_comes_back_up():
    scene, data, op = _scene()
    frames = op.sides["left"]["timeline"].frames
    i = _swing(frames)
    start, end = frames[i - 1].end_step, frames[i].end_step
    assert end - start == swing_steps(STRIKE_RISE_M + STRIKE_FOLLOW_M)
    # the wrist's speed along the planned swing, step by step, not the formula that planned it
    timeline = op.sides["left"]["timeline"]
    peak = max(np.linalg.norm(timeline.at(s + 1)[0] - timeline.at(s)[0]) for s in range(start, end)) * physics.CONTROL_HZ
    assert peak >= 1.5 * MIN_SPEED_M_S                # headroom for the arm's lag
    assert np.allclose(frames[i + 1].pos, frames[i - 1].pos)          # back up to where it swung from


def test_the_swing_aims_where_an_earlier_step_leaves_the_target():
    spot = [0.1, -0.2]
    moved = ({"hand": "right", "pick": "wood_block", "place": "table", "place_offset": spot},)
    (scene, data, op), (_, _, op_moved) = _scene(), _scene(moved)
    block = data.xpos[scene.object_body_ids["wood_block"]]
    ready, ready_moved = (o.sides["left"]["timeline"].frames[_swing(o.sides["left"]["timeline"].frames) - 1].pos
                          for o in (op, op_moved))
    assert np.allclose(ready_moved[:2] - ready[:2], np.array(spot) - block[:2], atol=1e-6)


def test_episode_strikes_the_block_once():
    scene, data, op = _scene()
    ep = EpisodeRecording(scene, data)
    frames = op.sides["left"]["timeline"].frames
    up = frames[_swing(frames) + 1].end_step          # swung and back up
    latched_at = None
    for step in range(up + 1):
        action = op.act(step, data)
        physics.step_control(scene.model, data, action)
        rec = ep.step(data, action)
        if rec.stage_latched[0] and latched_at is None:
            latched_at = step
    assert latched_at is not None, "struck_once never latched"
    assert rec.stage_value[0], "struck more than once"      # exactly one strike so far
