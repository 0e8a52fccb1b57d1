"""A pick's `fallback` (the step done another way where the arm cannot do it as written):
teleop/plan_steps/fallback.py. On
stationery_category_sorting the RM65 does every step as written (its timelines as without the fields); the Pandas
cannot turn the marker's end down (wrist joint 7 at its limit) nor reach the glue's turned side grasp (another
wrist branch), and plan those steps with their fallback fields."""

import dataclasses

import numpy as np
import pytest

from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task
from teleop.recorder import home
from teleop.scripted_operator import ScriptedOperator

TASK = "stationery_category_sorting"


def _parse(steps):
    task = load_task(TASK)
    return parse_plan("t.yaml", {"demo_plan": steps}, PlanScope(task.objects, task.zones, task.points))


def _steps(how: str):
    """The task's steps: as written ("plan"), without their fallbacks ("plain") or with them in place ("fallen")."""
    steps = [dict(s) for s in load_task(TASK).demo_plan]
    for s in steps:
        other = s.pop("fallback", None) if how != "plan" else None
        if how == "fallen" and other:
            s.update(other)
    return _parse(steps)


def _frames(embodiment: str, how: str):
    scene = demonstration_scene(TASK, embodiment, 0)
    scene.task = dataclasses.replace(scene.task, demo_plan=_steps(how))
    op = ScriptedOperator()
    op.reset(scene, home(scene))
    return {side: [(f.end_step, *np.round(f.pos, 9), *np.round(f.quat, 9), *np.round(f.hand, 9))
                   for f in s["timeline"].frames] for side, s in op.sides.items()}


@pytest.mark.parametrize("fallback, message", [
    ({"pick": "glue"}, "a non-empty mapping of pick fields other than"),
    ({}, "a non-empty mapping"),
    ({"pinch_fold": 0.5}, r"fallback: pinch_fold: .*no pinch_fold without grasp: flat_pinch"),
])
def test_check_refuses_a_fallback_that_is_no_pick(fallback, message):
    step = {**load_task(TASK).demo_plan[3], "fallback": fallback}
    with pytest.raises(SpecError, match=message):
        _parse([step])


@pytest.mark.parametrize("embodiment", ["rm65_revo2", "ur5_rh5dg2"])
def test_an_arm_that_does_the_steps_as_written_plans_them_unchanged(embodiment):
    """The UR5's wrists turn +-2 pi: the marker's turn, winding one to its limit, has the same pose a turn back
    (axis_place.turn_margin counts only joints of at most a full turn), so it falls back on nothing."""
    assert _frames(embodiment, "plan") == _frames(embodiment, "plain")


def test_an_arm_that_cannot_plans_the_fallbacks_and_nothing_of_the_first_try():
    planned = _frames("panda_orca", "plan")
    assert planned == _frames("panda_orca", "fallen")
    assert planned["right"] != _frames("panda_orca", "plain")["right"]

