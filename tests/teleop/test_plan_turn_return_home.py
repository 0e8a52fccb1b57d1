"""Plan step `turn`, field `return_home` (default true): with `false` the hand stays where it rose off
the link instead of going home, and the hand's next step sets off from there. The check refuses what is
not a flag; the keyframes are the plain turn's without its last move home; and on a 50 cm fridge door
pulled open past square (the hand ends on the door's outer side, home lies behind the door) the door
stays open, where the way home shoves it back."""

import dataclasses

import numpy as np
import pytest
import yaml

from sim import physics
from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from sim.scene.builder import build_scene, demonstration_scene
from sim.scene.sample import demonstration_sample, demonstration_seed
from sim.tasks import load_task, parse_task
from teleop.recorder import home
from teleop.scripted_operator import ScriptedOperator
from plan_runs import home_and_plan

MICROWAVE, SCHUNK, DOOR = "microwave_bowl_loading", "ur5_schunk", "microwave/door"
OPEN = {"hand": "left", "turn": DOOR, "to": 1.9, "speed": 0.15}
SHUT = {"hand": "left", "turn": DOOR, "to": 0.0, "speed": 0.15, "after": [0]}


def _plan(steps):
    task = load_task(MICROWAVE)
    return parse_plan("t.yaml", {"demo_plan": steps}, PlanScope(task.objects, task.zones, task.points))


def _left_frames(steps):
    scene = demonstration_scene(MICROWAVE, SCHUNK, 0)
    scene.task = dataclasses.replace(scene.task, demo_plan=_plan(steps))    # not load_task's cached one
    op = ScriptedOperator()
    op.reset(scene, home(scene))
    return op.sides["left"]["timeline"].frames, op.sides["left"]["home"][0]


@pytest.mark.parametrize("value", ["no", 0, None])
def test_check_refuses_a_return_home_that_is_not_a_flag(value):
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.return_home"):
        _plan([{**OPEN, "return_home": value}])


def test_the_hand_stays_risen_off_the_link_and_the_next_step_sets_off_from_there():
    plain, home_pos = _left_frames([OPEN, SHUT])
    stays, _ = _left_frames([{**OPEN, "return_home": False}, SHUT])
    alone, _ = _left_frames([OPEN])
    turn = len(alone) - 1                      # the turn's own frames, up to and including its move home
    assert np.allclose(plain[turn - 1].pos, home_pos), "the plain turn ends with the move home"
    for a, b in zip(plain[:turn - 1], stays[:turn - 1]):
        assert a.end_step == b.end_step and np.allclose(a.pos, b.pos) and np.allclose(a.quat, b.quat)
    risen = stays[turn - 2].pos
    assert np.linalg.norm(risen - home_pos) > 0.1, "risen off the door's handle, not at home"
    # the shutting turn's first keyframe (its approach) now sets off from the risen hand, not from home
    assert len(stays) == len(plain) - 1
    assert stays[turn - 1].end_step < plain[turn].end_step


# A 50 cm fridge's right door (the fridge_fruit_shelf_sorting layout the plan was tried on: fridge centred
# between the arms, a pull bar low on each door): the right hand pulls it open to 1.9 rad, past square, and
# ends on the door's outer side; home lies behind the door.
FRIDGE, SHADOW = "fridge_fruit_shelf_sorting", "ur5_shadow"
BAR = [{"shape": "box", "size": [0.05, 0.008, 0.008], "pos": [0.16, -0.074, -0.18]},
       {"shape": "box", "size": [0.006, 0.025, 0.008], "pos": [0.115, -0.049, -0.18]},
       {"shape": "box", "size": [0.006, 0.025, 0.008], "pos": [0.205, -0.049, -0.18]}]
PULL = {"hand": "right", "turn": "fridge/right_door", "to": 1.9, "speed": 0.15}
STEPS = 520                 # the pull ends by ~340 control steps; the move home takes the next 60


def _fridge(tmp_path, **fields):
    raw = yaml.safe_load(load_task(FRIDGE).source.read_text())
    fridge = raw["objects"]["fridge"]
    fridge["pose"] = {"xy": [0.0, 0.21]}
    fridge["parts"] = [{"open_box": {"size": [0.22, 0.17, 0.25], "wall": 0.015, "open": "-y"}},   # 44 cm wide
                       {"shape": "box", "size": [0.205, 0.155, 0.006], "pos": [0, 0.008, 0.0]}]
    for name, sign in (("right_door", -1.0), ("left_door", 1.0)):
        door = fridge["links"][name]
        door["pos"] = [-0.22 * sign, -0.17, 0.0]
        door["parts"] = [{"shape": "box", "size": [0.109, 0.012, 0.25], "pos": [0.109 * sign, -0.012, 0.0]}] + [
            {**p, "pos": [sign * p["pos"][0], *p["pos"][1:]]} for p in BAR]
    raw["objects"]["banana"]["pose"] = {"xy": [0.05, -0.3]}      # clear of the door's swing
    raw["objects"]["lemon"]["pose"] = {"xy": [-0.36, -0.05]}
    # the hand's next step (shutting it again) waits 10 s: without one, the plan's end sends every hand home
    raw["demo_plan"] = [{**PULL, **fields}, {**PULL, "to": 0.0, "wait_s": 10.0}]
    task = parse_task(raw, tmp_path / "fridge.yaml")
    scene = build_scene(task, SHADOW, demonstration_sample(task, demonstration_seed(FRIDGE, 0)))
    data, op = home_and_plan(scene)
    for step in range(STEPS):
        physics.step_control(scene.model, data, op.act(step, data))
    return float(data.qpos[scene.model.jnt_qposadr[scene.model.joint("fridge/right_door").id]])


def test_a_tall_door_pulled_open_stays_open_when_the_hand_stays(tmp_path):
    assert _fridge(tmp_path, return_home=False) > 1.6
    # going home it rises over the door as it now stands (teleop/transit.py), where it once shoved it back
    assert _fridge(tmp_path) > 1.5, "the way home goes over the door, not through it"
