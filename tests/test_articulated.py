"""Articulated objects behave like their real counterparts and the evaluator reads their joints."""

import mujoco
import numpy as np
import pytest
from task_scenes import settle

from evaluation import EpisodeEvaluator
from sim import physics
from sim.scene.parts import open_box, open_cylinder, parts_aabb
from sim.scene.state import SceneObserver
from sim.tasks import load_task


def _run(task: str, joint_values: dict, steps: int = 60, force: tuple[str, list] | None = None):
    s = settle(task, load_task(task).paper_embodiment, steps=0)
    scene, data = s.scene, s.data
    for joint, q in joint_values.items():
        data.qpos[scene.joint_qpos_adr[joint]] = q
    mujoco.mj_forward(scene.model, data)
    if force:
        data.xfrc_applied[scene.model.body(force[0]).id, :3] = force[1]
    for _ in range(steps):
        physics.step_control(scene.model, data, scene.layout.home_ctrl)
    return SceneObserver(scene).state(data).joints


@pytest.mark.parametrize("task,joint,start,check", [
    ("trash_disposal", "trash_can/lid", 0.6, lambda q: q < 0.05),                 # gravity shuts the lid
    ("toilet_lid_cleaner_pour", "toilet/lid", 1.62, lambda q: q > 1.6),           # past vertical it stays open
    ("fridge_wine_interhand_pour", "fridge/door", 1.0, lambda q: abs(q - 1.0) < 0.05),   # friction holds it
    ("faucet_cup_water_fill", "faucet/handle", 0.8, lambda q: abs(q - 0.8) < 0.05),
    ("gaming_desk_setup", "monitor/screen", 0.0, lambda q: abs(q) < 0.05),
    ("bimanual_piano_melody", "piano/G3", -0.009, lambda q: q > -0.0005),          # the spring lifts the key
    ("gaming_desk_setup", "keyboard/esc", -0.0028, lambda q: q > -0.0005),
    ("gaming_desk_setup", "mouse/left_button", -0.0018, lambda q: q > -0.0005),
])
def test_joints_rest_where_their_real_counterparts_do(task, joint, start, check):
    q = _run(task, {joint: start})[joint]
    assert check(q), q


def test_a_pushed_key_goes_down_and_a_pressed_melody_latches_its_stage():
    s = settle("bimanual_piano_melody", "xarm7_ability", steps=0)
    scene, data = s.scene, s.data
    observer = SceneObserver(scene)
    ev = EpisodeEvaluator(scene.task.metrics, observer.context, source=str(scene.task.source))
    lowest = 0.0
    for key in ["C3", "C3", "G3", "G3", "A3", "A3", "G3"]:
        body = scene.model.body(f"piano/{key}").id
        for push in (True, False):                  # 1.5 N for 0.25 s, then let go for 0.25 s
            data.xfrc_applied[body, 2] = -1.5 if push else 0.0
            for _ in range(15):
                physics.step_control(scene.model, data, scene.layout.home_ctrl)
                ev.update(observer.state(data), physics.CONTROL_DT)
                lowest = min(lowest, data.qpos[scene.joint_qpos_adr[f"piano/{key}"]])
    assert lowest < -0.008
    record = ev.result()
    assert record.stage_latched == [True, False]      # bass played, treble untouched
    assert not record.success


def test_object_masses_include_their_links():
    s = settle("fridge_fruit_shelf_sorting", "ur5_shadow", steps=0)
    model = s.scene.model
    fridge = s.scene.task.objects["fridge"]
    expected = fridge.mass + sum(link.mass for link in fridge.links)
    assert model.body_subtreemass[model.body("fridge").id] == pytest.approx(expected)
    assert model.body_subtreemass[model.body("banana").id] == pytest.approx(0.12)


def test_generated_shapes_fit_their_outer_size_and_know_their_cavity():
    parts, cavity = open_box([0.15, 0.1, 0.06], 0.01, "+z")
    lo, hi = parts_aabb(parts)
    assert np.allclose(lo, [-0.15, -0.1, -0.06]) and np.allclose(hi, [0.15, 0.1, 0.06])
    assert len(parts) == 5 and np.allclose(cavity.half_extents, [0.14, 0.09, 0.055])
    assert np.allclose(cavity.offset, [0, 0, 0.005])
    parts, cavity = open_box([0.2, 0.17, 0.23], 0.015, "-y")            # a cabinet opening forwards
    assert max(p.pos[1] for p in parts) > 0 and min(p.pos[1] for p in parts) > -0.17 + 0.015
    assert cavity.offset[1] < 0
    parts, cavity = open_cylinder([0.1, 0.045], 0.006, 16)
    lo, hi = parts_aabb(parts)
    assert np.allclose(hi[:2], 0.1, atol=2e-3) and np.allclose(lo[2], -0.045)
    assert np.hypot(*cavity.half_extents[:2]) <= 0.1 - 0.006 + 1e-9
