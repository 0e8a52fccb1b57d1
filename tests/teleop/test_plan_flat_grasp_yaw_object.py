"""`grasp_yaw_object: true` on a flat pinch: `grasp_yaw` counted from the object's own x axis as it lies, so the
tips meet its sides at the same angle however it was left turned (jigsaw's pieces, left turned 12-40 degrees:
counted from the world's +x, one angle put a fingertip on a piece's top or the folded ring finger under its edge
on some seeds and not others)."""

import numpy as np
import pytest

from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task, parse_task

from plan_runs import JIGSAW, JIGSAW_GREEN_TO_TABLE, home_and_plan
from task_files import task_file_with_plan

TASK, EMBODIMENT = JIGSAW
PICK = {**JIGSAW_GREEN_TO_TABLE, "grasp_yaw": 71}


def _raw(step: dict) -> dict:
    return task_file_with_plan(TASK, [step])


def test_grasp_yaw_object_is_parsed(tmp_path):
    step = parse_task(_raw({**PICK, "grasp_yaw_object": True}), tmp_path / "jigsaw.yaml").demo_plan[0]
    assert step["grasp_yaw_object"] is True and step["grasp_yaw"] == 71


@pytest.mark.parametrize(("step", "expected"), [
    ({**PICK, "grasp": "pinch", "grasp_yaw_object": True}, "no grasp_yaw_object without grasp: flat_pinch"),
    ({k: v for k, v in PICK.items() if k != "grasp_yaw"} | {"grasp_yaw_object": True}, "needs grasp_yaw in degrees"),
    ({**PICK, "grasp_yaw": "across", "grasp_yaw_object": True}, "needs grasp_yaw in degrees"),
])
def test_grasp_yaw_object_needs_a_flat_pinch_and_degrees(tmp_path, step, expected):
    with pytest.raises(SpecError, match=expected):
        parse_task(_raw(step), tmp_path / "jigsaw.yaml")


@pytest.mark.parametrize("hand,piece", [("right", "green_piece"), ("left", "red_piece")])
def test_the_hand_turns_with_the_object(hand, piece):
    """Counted from the object's x axis, the hand is turned as by the world angle plus the object's yaw."""
    from teleop.plan_steps.pick_place import flat_pinch
    scene = demonstration_scene(load_task(TASK), EMBODIMENT)
    data, op = home_and_plan(scene)
    body_rot = data.xmat[scene.object_body_ids[piece]].reshape(3, 3)
    yaw = float(np.degrees(np.arctan2(body_rot[1, 0], body_rot[0, 0])))
    assert abs(yaw) > 5.0        # the pieces lie turned: the two countings differ
    step = {**PICK, "hand": hand, "pick": piece}
    counted, _, at, _ = flat_pinch(op, data, {**step, "grasp_yaw_object": True}, piece)
    world, _, at_world, _ = flat_pinch(op, data, {**step, "grasp_yaw": 71 + yaw}, piece)
    assert np.allclose(counted, world, atol=1e-9) and np.allclose(at, at_world, atol=1e-9)
    unturned, _, _, _ = flat_pinch(op, data, step, piece)
    assert not np.allclose(counted, unturned, atol=1e-3)
