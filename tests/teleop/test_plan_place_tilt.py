"""Plan step `pick`, field `place_tilt_deg`: the check refuses it without `place_axis` and outside [0, 60]
degrees, naming the field; the planned lowering holds the object's `place_axis` that many degrees short
of straight down (a pen let go leaning into a pen cup, whose wall stands it up), and 0 is the full turn."""

import dataclasses

import mujoco
import numpy as np
import pytest

from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample, demonstration_seed
from sim.tasks import load_task
from teleop.plan_steps.axis_place import turn_down
from plan_runs import home_and_plan

TASK, EMBODIMENT = "stationery_category_sorting", "rm65_revo2"
PEN = {"hand": "left", "pick": "gray_pen", "place": "pen_cup", "place_offset": [0.0, 0.0, -0.05],
       "grasp": "flat_pinch", "grasp_point": [-0.055, 0.0, 0.0], "place_axis": [1.0, 0.0, 0.0], "place_tilt_deg": 40}
DOWN = np.array([0.0, 0.0, -1.0])


def _task(steps):
    spec = load_task(TASK)
    return dataclasses.replace(spec, demo_plan=parse_plan("t.yaml", {"demo_plan": steps},
                                                          PlanScope(spec.objects, spec.zones, spec.points)))


def _rot(q) -> np.ndarray:
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, q)
    return R.reshape(3, 3)


def test_check_refuses_a_tilt_without_place_axis():
    step = {k: v for k, v in PEN.items() if k != "place_axis"}
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.place_tilt_deg': expected no place_tilt_deg without place_axis"):
        _task([step])


@pytest.mark.parametrize("value", [-5, 75, "x"])
def test_check_refuses_a_tilt_out_of_range(value):
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.place_tilt_deg'"):
        _task([{**PEN, "place_tilt_deg": value}])


@pytest.mark.parametrize("short", [0.0, 40.0])
def test_turn_down_stops_short_of_straight_down(short):
    direction = np.array([0.6, 0.0, 0.8])       # 37 degrees from straight up
    turned = turn_down(direction, np.eye(3), short) @ direction
    assert np.degrees(np.arccos(turned @ DOWN)) == pytest.approx(short, abs=1e-6)


@pytest.mark.parametrize("tilt", [40, 0])
def test_the_planned_release_leaves_the_axis_tilted_over_the_cup(tilt):
    spec = _task([{**PEN, "place_tilt_deg": tilt}])
    scene = build_scene(spec, EMBODIMENT, demonstration_sample(spec, demonstration_seed(TASK, 0)))
    data, op = home_and_plan(scene)
    frames = op.sides["left"]["timeline"].frames
    in_hand = _rot(frames[2].quat).T @ data.xmat[scene.object_body_ids["gray_pen"]].reshape(3, 3)   # as grasped
    opened = next(i for i, f in enumerate(frames) if i > 3 and np.allclose(f.hand, op.sides["left"]["open"]))
    lowered = _rot(frames[opened - 1].quat) @ in_hand @ np.array([1.0, 0.0, 0.0])
    assert np.degrees(np.arccos(np.clip(lowered @ DOWN, -1.0, 1.0))) == pytest.approx(tilt, abs=1.0)
