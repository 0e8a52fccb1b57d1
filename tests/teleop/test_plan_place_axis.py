"""Plan step `pick`, field `place_axis`: the check refuses what is not a direction in the object's frame
(and a place_axis on an object slid in level from the front), naming the field; the planned lowering
holds the object with that axis straight down over its place, whichever end; and on the direct joint
path a marker lying on the table, pinched by its middle and turned on the way, ends upright in a pen
cup (stationery_category_sorting on the RM65+Revo2; the cup set where the task file puts it, within
both arms' reach, so that the test does not hang on the file's layout)."""

import dataclasses

import mujoco
import numpy as np
import pytest

from sim import physics
from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample, demonstration_seed
from sim.tasks import load_task
from plan_runs import home_and_plan

TASK, EMBODIMENT = "stationery_category_sorting", "rm65_revo2"
MARKER = {"hand": "right", "pick": "marker", "place": "pen_cup", "place_offset": [0.0, 0.0, -0.05],
          "grasp": "flat_pinch", "place_axis": [1.0, 0.0, 0.0]}
CUP_XY = (-0.03, -0.08)     # within both RM65 arms' reach with the marker held upright


def _task(steps, task: str = TASK):
    spec = load_task(task)
    if task == TASK:
        spec = dataclasses.replace(spec, objects={**spec.objects, "pen_cup": dataclasses.replace(
            spec.objects["pen_cup"], xy=CUP_XY)})
    return dataclasses.replace(spec, demo_plan=parse_plan("t.yaml", {"demo_plan": steps},
                                                          PlanScope(spec.objects, spec.zones, spec.points)))


@pytest.mark.parametrize("value", [[0.0, 0.0, 0.0], [1.0, 0.0], "x", [True, 0.0, 0.0]])
def test_check_refuses_a_place_axis_that_is_no_direction(value):
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.place_axis': expected (a non-zero )?\[x, y, z\]"):
        _task([{**MARKER, "place_axis": value}])


def test_check_refuses_a_place_axis_slid_in_from_the_front():
    step = {"hand": "right", "pick": "baguette", "place": "microwave", "place_from": "front", "place_axis": [0, 0, 1]}
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.place_axis': expected no place_axis with place_from: front"):
        _task([step], task="microwave_bowl_loading")


def _scene(steps, seed: int = 0):
    spec = _task(steps)
    return build_scene(spec, EMBODIMENT, demonstration_sample(spec, demonstration_seed(TASK, seed)))


def _rot(q) -> np.ndarray:
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, q)
    return R.reshape(3, 3)


@pytest.mark.parametrize("axis", [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], None])
def test_the_planned_release_holds_the_axis_down_over_the_cup(axis):
    step = {**MARKER, "place_axis": axis} if axis else {k: v for k, v in MARKER.items() if k != "place_axis"}
    scene = _scene([step])
    data, op = home_and_plan(scene)
    frames = op.sides["right"]["timeline"].frames
    body = scene.object_body_ids["marker"]
    in_hand = _rot(frames[2].quat).T @ data.xmat[body].reshape(3, 3)     # as it is grasped
    opened = next(i for i, f in enumerate(frames) if i > 3 and np.allclose(f.hand, op.sides["right"]["open"]))
    lowered = _rot(frames[opened - 1].quat) @ in_hand @ np.array([1.0, 0.0, 0.0])
    if axis is None:        # without place_axis it is carried as it lay
        assert abs(lowered[2]) < 0.2
        return
    assert lowered @ (-np.sign(axis[0]) * np.array([0.0, 0.0, 1.0])) > np.cos(np.radians(1.0))


def test_a_lying_marker_ends_upright_in_the_cup():
    scene = _scene([MARKER], seed=0)
    data, op = home_and_plan(scene)
    for step in range(op.length):
        physics.step_control(scene.model, data, op.act(step, data))
    marker, cup = (scene.object_body_ids[n] for n in ("marker", "pen_cup"))
    off = data.xpos[marker] - data.xpos[cup]
    assert np.hypot(*off[:2]) < 0.03 and abs(off[2]) < 0.04, f"marker {off.round(3)} from the cup's centre"
    tilt = np.degrees(np.arccos(abs(data.xmat[marker].reshape(3, 3)[2, 0])))
    assert tilt < 35.0, f"marker {tilt:.0f} degrees off vertical"
