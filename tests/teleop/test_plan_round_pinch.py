"""Pick field `round_pinch` (a pinch of a thin round object lying on the table: a pen, a marker, a battery): a hand
whose file declares `round_pinch` takes it with that flat pinch (the Schunk: thumb against index and middle, the
others folded half way), whatever the step's grasp; a hand that declares none plans the step as written (the
RM65+Revo2's stationery timelines do not change). The check refuses it off a pinch, and a hand file's
declaration with a finger no pinch closes against."""

import dataclasses

import numpy as np
import pytest

from sim.demo_plan import PlanScope, parse_plan
from sim.embodiment import load_embodiment
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.schema.hand import RoundPinch
from sim.tasks import load_task
from teleop.recorder import home
from teleop.scripted_operator import ScriptedOperator

TASK = "stationery_category_sorting"
BATTERY = {"hand": "right", "pick": "battery", "place": "plastic_box", "place_offset": [0.03, 0.0, 0.0],
           "grasp": "pinch"}


def _plan(steps):
    task = load_task(TASK)
    return parse_plan("t.yaml", {"demo_plan": steps}, PlanScope(task.objects, task.zones, task.points))


def _frames(embodiment: str, step: dict) -> list[tuple]:
    scene = demonstration_scene(TASK, embodiment, 0)
    scene.task = dataclasses.replace(scene.task, demo_plan=_plan([step]))     # not load_task's cached one
    op = ScriptedOperator()
    op.reset(scene, home(scene))
    return [(f.end_step, *np.round(f.pos, 9), *np.round(f.quat, 9), *np.round(f.hand, 9))
            for f in op.sides["right"]["timeline"].frames]


@pytest.mark.parametrize("fields", [{"grasp": "power"}, {"grasp": "side"}, {"round_pinch": "yes"}])
def test_check_refuses_round_pinch_off_a_pinch(fields):
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.round_pinch"):
        _plan([{**BATTERY, "round_pinch": True, **fields}])


@pytest.mark.parametrize("fields", [{"fingers": ["thumb"], "fold": 0.5}, {"fingers": [], "fold": 0.5},
                                    {"fingers": ["index"], "fold": 1.5}])
def test_a_hand_files_round_pinch_is_checked(fields):
    with pytest.raises(ValueError):
        RoundPinch(**fields)


def test_the_schunk_takes_it_with_its_declared_flat_pinch():
    declared = load_embodiment("ur5_schunk").hand.round_pinch
    assert declared.fingers == ("index", "middle") and declared.fold == 0.5
    flat = {**BATTERY, "grasp": "flat_pinch", "pinch_fingers": ["index", "middle"], "pinch_fold": 0.5}
    assert _frames("ur5_schunk", {**BATTERY, "round_pinch": True}) == _frames("ur5_schunk", flat)
    assert _frames("ur5_schunk", {**BATTERY, "round_pinch": True}) != _frames("ur5_schunk", BATTERY)


def test_a_hand_without_a_round_pinch_plans_the_step_as_written():
    assert load_embodiment("rm65_revo2").hand.round_pinch is None
    assert _frames("rm65_revo2", {**BATTERY, "round_pinch": True}) == _frames("rm65_revo2", BATTERY)


def test_a_declaration_left_empty_is_the_hands_own_flat_pinch():
    """`round_pinch: {}`: the step as a flat pinch with the hand's own fingers and fold (no pinch_fingers or
    pinch_fold added), for a hand whose flat pinch lifts what its pad pinch does not."""
    from sim.embodiment.hand_file import RoundPinch as Declared
    from teleop.plan_steps.pick import round_pinched

    assert RoundPinch().fingers is None and RoundPinch().fold is None

    class Operator:
        sides = {"right": {"round_pinch": Declared()}}
    assert round_pinched(Operator(), {**BATTERY, "round_pinch": True}) == {**BATTERY, "round_pinch": True,
                                                                           "grasp": "flat_pinch"}


def test_a_declared_tips_height_closes_the_tips_that_high():
    """The RH5DG2 declares its round pinch's tips 6 mm over the object's bottom (its linkage index, pressed onto the
    table with the default, stuck there): the step as a flat pinch with that grasp_tips_height_m."""
    declared = load_embodiment("ur5_rh5dg2").hand.round_pinch
    assert declared.fingers == ("index", "middle") and declared.fold is None and declared.tips_height_m == 0.006
    flat = {**BATTERY, "grasp": "flat_pinch", "pinch_fingers": ["index", "middle"], "grasp_tips_height_m": 0.006}
    assert _frames("ur5_rh5dg2", {**BATTERY, "round_pinch": True}) == _frames("ur5_rh5dg2", flat)
    with pytest.raises(ValueError):
        RoundPinch(tips_height_m=0.05)
