"""`drag` with `contact: palm`: the check refuses a bad contact and the hook's fields beside a palm push
(naming the field); the planned push stands the flat hand on its edge behind the container, on the far
side of its way (palm towards the way, fingers level, thumb up, lowest edge just above the table), and
pushes it the whole way to the zone."""

import mujoco
import numpy as np
import pytest
import yaml

from sim.errors import SpecError
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample, zone_centre
from sim.tasks import load_task, parse_task
from teleop.operator_motion import UP
from teleop.pinch_grasp import THUMB_TIP, fingertip_rows, fingertips_in_site_frame
from teleop.plan_steps.drag import PUSH_TIP_HEIGHT_M
from teleop.transit import hand_outline
from plan_runs import home_and_plan

TASK, EMBODIMENT = "fruit_bowl_loading", "ur5_rh56dfx"
PUSH = {"hand": "right", "drag": "bowl", "to_zone": "center", "contact": "palm"}


def _task(tmp_path, **fields):
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    raw["demo_plan"] = [{**PUSH, **fields}]
    return parse_task(raw, tmp_path / "bowl.yaml")


@pytest.mark.parametrize("field, value, expected", [
    ("contact", "fist", r"one of \['hook', 'palm'\]"), ("contact", 3, r"one of"),
    ("hook_depth", 0.03, r"no hook_depth with contact: palm"), ("pitch_deg", 40, r"no pitch_deg with contact: palm"),
    ("hook_closure", 0.5, r"no hook_closure with contact: palm")])
def test_palm_drag_refuses_bad_fields(tmp_path, field, value, expected):
    with pytest.raises(SpecError, match=rf"bowl.yaml: field 'demo_plan\[0\].{field}'.*{expected}"):
        _task(tmp_path, **{field: value})


def test_the_hook_keeps_its_fields(tmp_path):
    _task(tmp_path, contact="hook", hook_depth=0.03)      # the default contact takes them as before


def _rotation(quat: np.ndarray) -> np.ndarray:
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, quat)
    return R.reshape(3, 3)


def test_the_flat_hand_pushes_from_behind_on_its_edge_all_the_way_to_the_zone(tmp_path):
    task = _task(tmp_path)
    scene = build_scene(task, EMBODIMENT, demonstration_sample(task, 0))
    data, op = home_and_plan(scene)
    side = op.sides["right"]
    bowl = data.xpos[scene.object_body_ids["bowl"]].copy()
    goal = np.array([*zone_centre(task.zones["center"]), bowl[2]])
    d = goal - bowl
    d /= np.linalg.norm(d)
    outline = hand_outline(side["hand"], "right", side["open"])
    thumb = fingertips_in_site_frame(side["hand"], side["open"])[fingertip_rows(side["hand"], (THUMB_TIP,))[0]]
    # the push: the frames whose hand's lowest point is at the push height (set down, pushed, backed off)
    low = [(f.pos, _rotation(f.quat)) for f in side["timeline"].frames
           if abs((f.pos + outline @ _rotation(f.quat).T)[:, 2].min() - (scene.table_height + PUSH_TIP_HEIGHT_M)) < 1e-6]
    assert len(low) == 3, "no set-down, push and back-off at the push height"
    for _, R in low:
        assert R[:, 1] @ d > 1 - 1e-6, "palm not towards the way"
        assert abs(R[:, 2] @ UP) < 1e-6, "fingers not level"
        assert (R @ thumb)[2] > 0, "thumb not up"
    (set_down, R), (pushed, _) = low[0], low[1]
    front = float(np.max(outline @ R.T @ d))             # the hand's foremost point along the way
    radius = float(np.asarray(task.objects["bowl"].half_extents)[0])
    assert (set_down - bowl) @ d + front < -radius, "the hand does not come down behind the bowl"
    # at the end of the push the foremost point is about one radius (the wall at the foot) short of the goal
    assert abs((goal - pushed) @ d - front - radius) < 0.03
