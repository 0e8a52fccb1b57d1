"""Step field `park_out_m` (any kind): where the other arm's planned path goes into a hand resting at home,
the hand waits for its `after` steps (back home as the wait ends) and rests after its last step that far
outward instead. On stationery_category_sorting the JAKA's right forearm, standing the marker in the cup,
goes 1-5 cm into the left hand at home; the RM65's keeps clear (within 7 mm), so its timelines do not change.
Without the field nothing changes."""

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


def _plan(park_out_m: float | None):
    task = load_task(TASK)
    steps = [dict(s) for s in task.demo_plan]
    for s in steps:
        s.pop("park_out_m", None)
        if park_out_m is not None and s["pick"] in ("battery", "gray_pen"):
            s["park_out_m"] = park_out_m
    return parse_plan("t.yaml", {"demo_plan": steps}, PlanScope(task.objects, task.zones, task.points))


def _sides(embodiment: str, park_out_m: float | None):
    scene = demonstration_scene(TASK, embodiment, 0)
    scene.task = dataclasses.replace(scene.task, demo_plan=_plan(park_out_m))
    op = ScriptedOperator()
    op.reset(scene, home(scene))
    return op.sides


def _frames(side):
    return [(f.end_step, *np.round(f.pos, 9), *np.round(f.quat, 9), *np.round(f.hand, 9)) for f in side["timeline"].frames]


def test_check_refuses_a_park_out_of_range():
    task = load_task(TASK)
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.park_out_m"):
        parse_plan("t.yaml", {"demo_plan": [{**task.demo_plan[0], "park_out_m": 0.5}]},
                   PlanScope(task.objects, task.zones, task.points))


def test_a_hand_in_the_other_arms_way_waits_and_rests_outward():
    plain, parked = _sides("jaka_zu7_dexhand021", None), _sides("jaka_zu7_dexhand021", 0.1)
    left, home_pos = parked["left"]["timeline"].frames, parked["left"]["home"][0]
    # the left waits 10 cm further left (away from the right arm), back home as the pen's step sets off
    assert np.allclose(left[1].pos, home_pos + [-0.1, 0, 0]) and np.allclose(left[3].pos, home_pos)
    assert _frames(parked["left"])[4:] == _frames(plain["left"])[2:]        # the same pen and glue steps
    # the right, done, rests 10 cm further right: the left forearm putting the pen in reaches its home
    assert np.allclose(parked["right"]["timeline"].frames[-1].pos, parked["right"]["home"][0] + [0.1, 0, 0])
    assert _frames(parked["right"])[:-1] == _frames(plain["right"])[:-1]


def test_nothing_changes_where_the_other_arm_keeps_clear():
    plain, parked = _sides("rm65_revo2", None), _sides("rm65_revo2", 0.1)
    for side in ("left", "right"):
        assert _frames(parked[side]) == _frames(plain[side])


def _fridge_sides(embodiment: str, park: bool):
    task = load_task("fridge_fruit_shelf_sorting")
    steps = [dict(s) for s in task.demo_plan]
    for s in steps:
        if not park:
            s.pop("park_out_m", None)
    plan = parse_plan("t.yaml", {"demo_plan": steps}, PlanScope(task.objects, task.zones, task.points))
    scene = demonstration_scene("fridge_fruit_shelf_sorting", embodiment, 0)
    scene.task = dataclasses.replace(scene.task, demo_plan=plan)
    op = ScriptedOperator()
    op.reset(scene, home(scene))
    return op.sides


def test_the_other_arms_path_is_counted_where_it_picks_up_what_an_earlier_step_put_down():
    # fridge_fruit_shelf_sorting: the right hand picks the banana up a second time where its first step set it
    # down, on the desk's left (planned where it lay at the start, re-aimed at episode time); on the RH5DG2 its
    # wrist links go into the left arm resting at home there, so the left, done with its door, rests outward
    parked = _fridge_sides("ur5_rh5dg2", True)["left"]
    assert np.allclose(parked["timeline"].frames[-1].pos, parked["home"][0] + [-0.2, 0, 0])
    # where the right arm keeps clear (the Shadow on this seed), the timelines do not change
    plain, shadow = _fridge_sides("ur5_shadow", False), _fridge_sides("ur5_shadow", True)
    for side in ("left", "right"):
        assert _frames(shadow[side]) == _frames(plain[side])
