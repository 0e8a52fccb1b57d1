"""`grasp: side` for pick: the plan check, the hand's path (down beside the object from above its top, in
level, out level after letting go) and a real lift of a 1.2 kg drill standing on its battery by its grip."""

import dataclasses

import mujoco
import numpy as np
import pytest

from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task, parse_task
from teleop.plan_steps.pick_place import SIDE_GRASP_IN_M

from plan_runs import home_and_plan, rise_through_lift
from task_files import task_file_with_plan

TASK, EMBODIMENT = "tool_box_loading", "panda_orca"
PICK = {"hand": "right", "pick": "drill", "place": "box", "place_offset": [0.0, 0.0, -0.06], "grasp": "side",
        "grasp_roll_deg": 110, "grasp_point": [-0.03, 0, -0.012]}


def _raw(step: dict) -> dict:
    return task_file_with_plan(TASK, [step])


def test_side_is_a_pick_grasp(tmp_path):
    assert parse_task(_raw(dict(PICK)), tmp_path / "tool_box.yaml").demo_plan[0]["grasp"] == "side"


@pytest.mark.parametrize(("step", "expected"), [
    ({**PICK, "grasp": "power"}, "grasp_roll_deg'.*no grasp_roll_deg without grasp: side"),
    ({**PICK, "grasp_roll_deg": 150}, r"grasp_roll_deg'.*degrees in \[60, 135\]"),
])
def test_a_side_grasp_roll_is_checked(tmp_path, step, expected):
    with pytest.raises(SpecError, match=rf"tool_box.yaml: field 'demo_plan\[0\].{expected}"):
        parse_task(_raw(step), tmp_path / "tool_box.yaml")


def _operator(step: dict):
    spec = load_task(TASK)
    objects = dict(spec.objects)
    objects["drill"] = dataclasses.replace(objects["drill"], xy=(0.30, 0.05))     # within the right arm's easy reach
    spec = dataclasses.replace(spec, objects=objects, demo_plan=[step])
    scene = demonstration_scene(spec, EMBODIMENT)
    data, op = home_and_plan(scene)
    return scene, data, op


def _rotation(frame) -> np.ndarray:
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, frame.quat)
    return R.reshape(3, 3)


def test_a_side_grasp_comes_down_beside_the_object_and_moves_in_and_out_level():
    """The hand turned grasp_roll_deg about its fingers comes down, from above the drill's top, to
    SIDE_GRASP_IN_M out along its palm's normal, moves in level to the grip; let go, it moves out level
    the same way before it rises."""
    scene, data, op = _operator(dict(PICK))
    frames = op.sides["right"]["timeline"].frames
    normal = _rotation(frames[3])[:, 1]                 # wrist-site y: out of the palm
    assert np.degrees(np.arccos(np.clip(-normal[0], -1, 1))) == pytest.approx(20.0, abs=0.5)  # 110: 20 past level
    beside, grasp = next((a, b) for a, b in zip(frames, frames[1:])
                         if np.allclose(b.pos - a.pos, SIDE_GRASP_IN_M * normal, atol=1e-9))
    drill = scene.object_body_ids["drill"]
    above = frames[frames.index(beside) - 1]
    assert np.allclose(above.pos[:2], beside.pos[:2]) and above.pos[2] > data.xpos[drill][2] + 0.09   # over its top
    outs = [(a, b) for a, b in zip(frames, frames[1:])
            if np.allclose(b.pos - a.pos, -SIDE_GRASP_IN_M * _rotation(b)[:, 1], atol=1e-9)]
    assert len(outs) == 1 and outs[0][0].end_step > grasp.end_step


def test_a_side_grasp_lifts_a_drill_by_its_grip():
    """The 1.2 kg drill standing on its battery, taken by its grip under the motor, is lifted clear
    of the table (direct joint path, seed 0)."""
    scene, data, op = _operator(dict(PICK))
    assert rise_through_lift(scene, data, op, "drill") > 0.08
