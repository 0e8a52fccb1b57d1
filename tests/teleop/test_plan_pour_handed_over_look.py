"""Plan step `pour` of a bottle the other hand gave (`handover`, then `pour` with the bottle in hand): before
tipping it, the operator looks where the bottle's mouth is in its hand (it hangs leaning or lower than the
handover planned) and moves the tilt's keyframes so that, tipped, the mouth comes over the target. On
fridge_wine_interhand_pour the bottle leant 3 cm off in the right hand and the tipped mouth missed the glass's
6 cm radius (7.3 cm off)."""

import mujoco
import numpy as np
import yaml

from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample, demonstration_seed
from sim.tasks import load_task, parse_task
from teleop.plan_steps.pour import aim_point, mouth_local
from teleop.recorder import home
from teleop.scripted_operator import ScriptedOperator

TASK, EMBODIMENT = "fridge_wine_interhand_pour", "ur5_rh5dg2"
# the plan tried on this setting (/work/helpers/s31/fridge_wine_interhand_pour.best.yaml): open the door, take the
# bottle out by its neck and hand it to the right by its bottom, pour (kept in hand), hand it back, put it back
PLAN = [{"hand": "left", "turn": "fridge/door", "to": 1.7, "speed": 0.15},
        {"hand": "left", "handover": "wine_bottle", "to_hand": "right", "at": [0.0, -0.12, 0.3], "pick_from": "front",
         "grasp": "side", "grasp_point": [0.0, 0.0, 0.1], "take_point": [0.0, 0.0, -0.13], "take_roll_deg": 120},
        {"hand": "right", "pour": "wine_bottle", "into": "glass", "hold": True, "tilt_deg": 62, "tilt_toward": [-1.0, 0.0]},
        {"hand": "right", "handover": "wine_bottle", "to_hand": "left", "at": [0.0, -0.12, 0.3],
         "take_point": [0.0, 0.0, 0.08]},
        {"hand": "left", "pick": "wine_bottle", "place": "fridge", "place_from": "front", "place_offset": [0.05, 0.02]}]


def _rot(quat) -> np.ndarray:
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, quat)
    return R.reshape(3, 3)


def test_the_tipped_mouth_is_moved_over_the_glass_by_where_it_sits_in_the_hand(tmp_path):
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    raw["demo_plan"] = PLAN[:3]              # open the door, take out and hand over, pour (kept)
    task = parse_task(raw, tmp_path / "fridge.yaml")
    scene = build_scene(task, EMBODIMENT, demonstration_sample(task, demonstration_seed(TASK, 0)))
    data = home(scene)
    op = ScriptedOperator()
    op.reset(scene, data)
    side = op.sides["right"]
    looks = [(step, fn) for step, fn in side["looks"] if fn.__qualname__.startswith("mouth_over_target")]
    assert len(looks) == 1, "one look, before the tilt"
    step, look = looks[0]
    frames = side["timeline"].frames
    over = next(k for k, f in enumerate(frames) if f.end_step == step)
    tilt, hold = frames[over + 1], frames[over + 2]
    # the bottle as the pour planned it in the hand (kept there: hold), its mouth 3 cm off along world y
    held = op.held["right"]
    name, offset, rotation = held.name, held.offset, held.rotation
    obj = scene.task.objects[name]
    planned = _rot(frames[over].quat).T @ (offset + rotation @ mouth_local(obj))        # wrist frame
    sits = planned + _rot(frames[over].quat).T @ np.array([0.0, 0.03, 0.0])
    # put the bottle there in `data`, relative to where the right wrist site is in it
    site = side["wrist_site_id"]
    body = scene.object_body_ids[name]
    mouth = data.site_xpos[site] + data.site_xmat[site].reshape(3, 3) @ sits
    adr = scene.model.jnt_qposadr[scene.model.body_jntadr[body]]
    R_bottle = data.xmat[body].reshape(3, 3)
    data.qpos[adr:adr + 3] = mouth - R_bottle @ mouth_local(obj)
    mujoco.mj_kinematics(scene.model, data)
    aim = aim_point(op, data, "glass")

    def tipped_mouth(frame):
        return (frame.pos + _rot(frame.quat) @ sits)[:2]

    assert np.linalg.norm(tipped_mouth(tilt) - aim) > 0.02, "as planned the mouth would miss the aim"
    look(data)
    for frame in (tilt, hold):
        assert np.linalg.norm(tipped_mouth(frame) - aim) < 1e-6
