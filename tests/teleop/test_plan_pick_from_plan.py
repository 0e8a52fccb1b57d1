"""`from_plan: true` on a `pick`: the grasp is planned where an earlier step of the plan leaves the object
(a mug pushed under a faucet's spout and out again by `drag`), not where it lay at the start. Planned
from the start, the operator's look moved the grasp to the mug but not the carry's transit, which rose
from the start and swung the hand (and mug) back towards it, into the faucet. Planning only: no physics."""

import dataclasses

import numpy as np

from sim.demo_plan import PlanScope, parse_plan
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample, demonstration_seed
from sim.tasks import load_task
from plan_runs import home_and_plan

TASK, EMBODIMENT = "faucet_cup_water_fill", "rm65_revo2"
ZONES = {"under_faucet": {"xy_min": [0.3, 0.05], "xy_max": [0.34, 0.09]},      # under the spout's end
         "faucet_left": {"xy_min": [0.13, 0.05], "xy_max": [0.17, 0.09]}}


def _mug_pick(from_plan: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(the mug at the start, where the second drag leaves it, the right wrist's keyframes from the mug
    pick's lift on): the mug, right of the faucet, pushed under it, out to its left and picked onto the tray."""
    spec = load_task(TASK)
    objects = {**spec.objects, "mug": dataclasses.replace(spec.objects["mug"], xy=(0.45, 0.07), yaw_deg=180.0),
               "tray": dataclasses.replace(spec.objects["tray"], xy=(0.05, -0.2))}
    steps = [{"hand": "right", "drag": "mug", "to_zone": "under_faucet", "contact": "palm"},
             {"hand": "right", "drag": "mug", "to_zone": "faucet_left", "contact": "palm", "after": [0]},
             {"hand": "right", "pick": "mug", "place": "tray", "from_plan": from_plan, "after": [1]}]
    zones = {**spec.zones, **ZONES}
    plan = parse_plan("test", {"demo_plan": steps}, PlanScope(objects, zones, spec.points))
    spec = dataclasses.replace(spec, objects=objects, zones=zones, demo_plan=plan)
    scene = build_scene(spec, EMBODIMENT, demonstration_sample(spec, demonstration_seed(TASK, 0)))
    data, op = home_and_plan(scene)
    side = op.sides["right"]
    # the pick's look at the mug as the hand sets off (the last at the mug; the drags' come before it)
    sets_off, _, planned, frames = [r for r in side["reaims"] if r[1] == "mug"][-1]
    start = data.xpos[scene.object_body_ids["mug"]].copy()
    left = op.planned_place(data, "mug", sets_off)[0]
    wrist = np.array([f.pos for f in side["timeline"].frames[frames.stop - 1:]])   # the lift, the carry, ...
    assert np.allclose(planned[:2], (left if from_plan else start)[:2])
    return start, left, wrist


def test_pick_from_plan_grasps_where_the_drag_leaves_the_mug():
    start, left, wrist = _mug_pick(True)
    assert start[0] - left[0] > 0.2               # the drags move it 30 cm left
    assert wrist[:, 0].max() < left[0] + 0.1      # no keyframe goes back towards where it started


def test_without_it_the_carry_rises_from_where_the_mug_started():
    start, left, wrist = _mug_pick(False)
    assert wrist[:, 0].max() > start[0] - 0.05
