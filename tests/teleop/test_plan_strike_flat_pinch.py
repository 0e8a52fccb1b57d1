"""`strike` with `grasp: flat_pinch`: screwdriver_box_hammer's 0.6 kg hammer lying flat, which no palm
grasp of the RH56DFX lifted, is taken by a flat pinch at its balance point and taps the block once."""

import dataclasses

import numpy as np
import pytest

from sim import physics
from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task
from teleop.plan_steps.strike import STRIKE_FOLLOW_M, STRIKE_RISE_M
from teleop.demos import DEFAULT_OPERATOR, OPERATORS
from teleop.recorder import EpisodeRecording, home

TASK, EMBODIMENT = "screwdriver_box_hammer", "ur5_rh56dfx"
STEP = {"hand": "left", "strike": "wood_block", "tool": "hammer", "strike_point": [0.15, 0.0, -0.018],
        "place": "box", "grasp": "flat_pinch", "grasp_point": [0.05, 0.0, 0.0],
        "grasp_squeeze_m": 0.03}     # the tips pressed past each other: it slides out of a bare meeting (test_plan_grasp_squeeze.py)


def _plan(task, **fields):
    return parse_plan("t.yaml", {"demo_plan": [{**STEP, **fields}]}, PlanScope(task.objects, task.zones, task.points))


def test_a_strike_takes_a_flat_pinch_at_a_grasp_point():
    task = load_task(TASK)
    assert _plan(task)[0]["grasp"] == "flat_pinch"
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.approach_pitch_deg"):
        _plan(task, approach_pitch_deg=20)      # the flat pinch turns its tips down to the table itself


def test_the_flat_pinched_hammer_strikes_the_block_once():
    spec = load_task(TASK)
    stage = next(s for s in spec.metrics["stages"] if s["id"] == "block_struck")
    metrics = {**spec.metrics, "stages": [{"id": "block_struck", "predicate": stage["predicate"]}],
               "terminal": {"latched": "block_struck"}}
    spec = dataclasses.replace(spec, metrics=metrics, demo_plan=_plan(spec))
    scene = demonstration_scene(spec, EMBODIMENT)
    data = home(scene)
    op = OPERATORS[DEFAULT_OPERATOR]()     # the stream path the demonstrations are recorded on
    op.reset(scene, data)
    ep = EpisodeRecording(scene, data, stream_settings=op.stream_settings)
    hammer = scene.object_body_ids["hammer"]
    rest_z = float(data.xpos[hammer][2])
    frames = op.plan.sides["left"]["timeline"].frames
    down = STRIKE_RISE_M + STRIKE_FOLLOW_M
    swing = next(i for i in range(1, len(frames))
                 if np.allclose(frames[i - 1].pos - frames[i].pos, [0.0, 0.0, down], atol=1e-9))
    latched_at, top = None, rest_z
    for step in range(frames[swing + 1].end_step + 1):        # swung and back up
        action = op.act(step, data)
        physics.step_control(scene.model, data, action)
        rec = ep.step(data, action, op.step_flags, op.step_reasons, stream=op.stream_step)
        top = max(top, float(data.xpos[hammer][2]))
        if rec.stage_latched[0] and latched_at is None:
            latched_at = step
    assert top - rest_z > 0.1, "the hammer was not lifted"
    assert latched_at is not None, "struck_once never latched"
    assert rec.stage_value[0], "struck more than once"
    assert float(data.xpos[hammer][2]) - rest_z > 0.05, "the hammer left the hand at the strike"
