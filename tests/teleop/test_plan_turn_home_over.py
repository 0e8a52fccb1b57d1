"""Plan step `turn`: the hand's way home after letting go of the link rises over what stands in the way,
the link as the turn leaves it included (teleop/transit.py), as every other move between steps does. On
fridge_wine_interhand_pour's 46 cm fridge the left hand pulls the door open past square by its bar and
ends on the door's outer side, home lies behind the door: the way home goes up over the door's top and
comes down at home (a straight move home shoved the door shut)."""

import numpy as np
import yaml

from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample, demonstration_seed
from sim.tasks import load_task, parse_task
from plan_runs import home_and_plan

TASK, EMBODIMENT = "fridge_wine_interhand_pour", "ur5_rh5dg2"
PULL = {"hand": "left", "turn": "fridge/door", "to": 1.9, "speed": 0.15}


def _left(tmp_path, steps):
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    raw["demo_plan"] = steps
    task = parse_task(raw, tmp_path / "fridge.yaml")
    scene = build_scene(task, EMBODIMENT, demonstration_sample(task, demonstration_seed(TASK, 0)))
    data, op = home_and_plan(scene)
    door = scene.model.joint("fridge/door").id
    top = max(float(data.geom_xpos[g][2] + scene.model.geom_aabb[g, 5]) for g in range(scene.model.ngeom)
              if scene.model.geom_bodyid[g] == scene.model.jnt_bodyid[door])
    return op.sides["left"], top


def test_the_way_home_rises_over_the_door_it_pulled_open(tmp_path):
    side, door_top = _left(tmp_path, [PULL])
    frames = side["timeline"].frames
    stays, _ = _left(tmp_path, [{**PULL, "return_home": False}])
    released = len(stays["timeline"].frames) - 2     # risen off the bar (then only the plan's end: home)
    risen = frames[released].pos
    assert np.allclose(risen, stays["timeline"].frames[released].pos)
    up, across, down = frames[released + 1:released + 4]
    assert np.allclose(up.pos[:2], risen[:2]) and up.pos[2] > risen[2] + 0.03, "first straight up"
    assert np.allclose(across.pos[:2], side["home"][0][:2]) and across.pos[2] > door_top, "across over the door"
    assert np.allclose(down.pos, side["home"][0]), "down at home"
