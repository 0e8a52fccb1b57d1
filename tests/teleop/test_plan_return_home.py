"""Pick field `return_home: true`: once it has let go the hand goes back to its home pose instead of waiting
risen over the place. On tool_box_loading the right hand, left over the box after placing the drill, met the
left arm carrying the wrench in (the arms' links touched on 6 control steps of ur5_rh56dfx seed 0). The check
refuses it with `hold: true` (the hand keeps the object); without the field nothing changes."""

import dataclasses

import numpy as np
import pytest

from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task
from teleop.recorder import home
from teleop.scripted_operator import ScriptedOperator

TASK, EMBODIMENT = "tool_box_loading", "panda_orca"
PICK = {"hand": "right", "pick": "flat_screwdriver", "place": "box", "place_offset": [0.0, -0.05],
        "grasp": "flat_pinch", "grasp_point": [-0.045, 0, 0]}


def _plan(steps):
    task = load_task(TASK)
    return parse_plan("t.yaml", {"demo_plan": steps}, PlanScope(task.objects, task.zones, task.points))


def _right_frames(step: dict):
    scene = demonstration_scene(TASK, EMBODIMENT, 0)
    scene.task = dataclasses.replace(scene.task, demo_plan=_plan([step]))     # not load_task's cached one
    op = ScriptedOperator()
    op.reset(scene, home(scene))
    side = op.sides["right"]
    return side["timeline"].frames, side


def test_check_refuses_return_home_with_hold():
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.return_home"):
        _plan([{**PICK, "place": "table", "place_offset": [0.1, -0.1, 0.05], "hold": True, "return_home": True}])


def test_the_hand_goes_home_after_letting_go():
    plain, side = _right_frames(PICK)
    back, _ = _right_frames({**PICK, "return_home": True})
    assert [f.end_step for f in back[:len(plain) - 1]] == [f.end_step for f in plain[:-1]]    # the same pick
    # plain: risen over the box until the plan's end sends it home; with the field: home at the step's end
    assert np.linalg.norm(plain[-2].pos - side["home"][0]) > 0.1
    assert np.allclose(back[-2].pos, side["home"][0]) and np.allclose(back[-2].hand, side["open"])
