"""Plan step `turn`, field `approach_over` (opt-in, default false): the hand comes to the link from above
its top, over whatever is in the way, the link as an earlier turn left it included. On
fridge_wine_interhand_pour the left hand pulls the fridge door open past square by its bar; shutting it
again, it pulls the bar from the door's outer side, and home lies behind the door: the straight move there
sweeps the hand through the door (it shoved the door to its limit and rode on its top edge)."""

import mujoco
import numpy as np
import pytest
import yaml

from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample, demonstration_seed
from sim.tasks import load_task, parse_task
from teleop.transit import CLEARANCE_M, hand_outline
from plan_runs import home_and_plan

TASK, EMBODIMENT = "fridge_wine_interhand_pour", "ur5_rh5dg2"
OPEN = {"hand": "left", "turn": "fridge/door", "to": 1.7, "speed": 0.15}
SHUT = {"hand": "left", "turn": "fridge/door", "to": 0.0, "speed": 0.15}


def _left(tmp_path, **fields):
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    raw["demo_plan"] = [OPEN, {**SHUT, **fields}]
    task = parse_task(raw, tmp_path / "fridge.yaml")
    scene = build_scene(task, EMBODIMENT, demonstration_sample(task, demonstration_seed(TASK, 0)))
    data, op = home_and_plan(scene)
    model, door = scene.model, scene.model.joint("fridge/door").id
    top = max(float(data.geom_xpos[g][2] + model.geom_aabb[g, 5]) for g in range(model.ngeom)
              if model.geom_bodyid[g] == model.jnt_bodyid[door])     # a vertical hinge: the same at any angle
    return op.sides["left"], top


@pytest.mark.parametrize("value", ["yes", 2, None])
def test_check_refuses_an_approach_over_that_is_not_a_flag(value):
    task = load_task(TASK)
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.approach_over"):
        parse_plan("t.yaml", {"demo_plan": [{**SHUT, "approach_over": value}]},
                   PlanScope(task.objects, task.zones, task.points))


def test_the_hand_comes_over_the_door_to_its_outer_side(tmp_path):
    plain, door_top = _left(tmp_path)
    over, _ = _left(tmp_path, approach_over=True)
    P, O = plain["timeline"].frames, over["timeline"].frames
    i = next(k for k, (p, o) in enumerate(zip(P, O)) if not np.allclose(p.pos, o.pos))
    approach, at_home = P[i].pos, over["home"][0]
    assert np.allclose(P[i - 1].pos, at_home), "plain: one straight move from home to beside the bar"
    lift, above, down = O[i:i + 3]
    assert np.allclose(lift.pos[:2], at_home[:2]) and lift.pos[2] > at_home[2] + 0.2, "first up at home"
    assert np.allclose(above.pos[:2], approach[:2]) and np.allclose(down.pos, approach), "across, then down to it"
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, above.quat)
    lowest = float(np.min((hand_outline(over["hand"], "left", over["open"]) @ R.reshape(3, 3).T)[:, 2]))
    assert above.pos[2] + lowest >= door_top + CLEARANCE_M - 1e-9, "the whole open hand clear of the door's top"
    assert len(O) == len(P) + 2 and O[-1].end_step > P[-1].end_step
