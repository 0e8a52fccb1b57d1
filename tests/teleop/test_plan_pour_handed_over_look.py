"""Plan step `pour` of a bottle the other hand gave (`handover`, then `pour` with the bottle in hand): before
tipping it, the operator looks where the bottle's mouth is in its hand (it hangs leaning or lower than the
handover planned) and moves the tilt's keyframes so that, tipped, the mouth comes over the target. On
fridge_wine_interhand_pour the bottle leant 3 cm off in the right hand and the tipped mouth missed the glass's
6 cm radius (7.3 cm off)."""

import mujoco
import numpy as np

from sim.scene.parts import quat_matrix
from teleop.plan_steps.pour import aim_point, mouth_local

from fridge_wine_plan import PLAN, planned_scene


def test_the_tipped_mouth_is_moved_over_the_glass_by_where_it_sits_in_the_hand(tmp_path):
    scene, data, op = planned_scene(PLAN[:3], tmp_path)    # open the door, take out and hand over, pour (kept)
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
    planned = quat_matrix(frames[over].quat).T @ (offset + rotation @ mouth_local(obj))        # wrist frame
    sits = planned + quat_matrix(frames[over].quat).T @ np.array([0.0, 0.03, 0.0])
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
        return (frame.pos + quat_matrix(frame.quat) @ sits)[:2]

    assert np.linalg.norm(tipped_mouth(tilt) - aim) > 0.02, "as planned the mouth would miss the aim"
    look(data)
    for frame in (tilt, hold):
        assert np.linalg.norm(tipped_mouth(frame) - aim) < 1e-6
