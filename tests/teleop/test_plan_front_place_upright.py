"""`place_from: front` on a `pick` of a held object: outside the opening the operator looks how the object
sits in the hand, where and how it leans, and turns the hand so that it goes in upright and is let go
where planned. On fridge_wine_interhand_pour the bottle handed back hung 25 degrees off upright in the left
hand and, set into the fridge so, leant against the back wall (not upright: the stage failed)."""

import mujoco
import numpy as np

from sim.scene.parts import quat_matrix
from teleop.operator_motion import UP, axis_rotation
from teleop.plan_steps.front_place import RELEASE_GAP_M

from fridge_wine_plan import PLAN, planned_scene
from plan_runs import front_slide_look


NAME = "wine_bottle"


def test_the_bottle_goes_in_upright_and_where_planned(tmp_path):
    scene, data, op = planned_scene(PLAN, tmp_path)    # up to the bottle put back through the front (held: handed back)
    side = op.sides["left"]
    look, slide, lower = front_slide_look(side)
    placed = next(pos for _, name, pos, on in op.moves if name == NAME and on == "fridge") + RELEASE_GAP_M * UP
    offset = placed - lower.pos             # the bottle's centre from the wrist as planned (world)
    # in `data`, the bottle in the left hand 5 mm lower than planned and leaning 25 degrees
    hand_rot = quat_matrix(slide.quat)
    site = side["wrist_site_id"]
    wrist_rot, wrist = data.site_xmat[site].reshape(3, 3), data.site_xpos[site]
    at = hand_rot.T @ (offset - 0.005 * UP)                                   # wrist frame
    lean = axis_rotation(np.array([1.0, 0.0, 0.0]), np.radians(25.0))
    body = scene.object_body_ids[NAME]
    up_local = data.xmat[body].reshape(3, 3).T @ UP
    in_hand = hand_rot.T @ lean @ data.xmat[body].reshape(3, 3)                 # its rotation in the hand
    adr = scene.model.jnt_qposadr[scene.model.body_jntadr[body]]
    data.qpos[adr:adr + 3] = wrist + wrist_rot @ at
    R = wrist_rot @ in_hand
    mujoco.mju_mat2Quat(data.qpos[adr + 3:adr + 7], R.flatten())
    mujoco.mj_kinematics(scene.model, data)

    def bottle_up(frame):
        return quat_matrix(frame.quat) @ in_hand @ up_local

    assert bottle_up(lower) @ UP < np.cos(np.radians(20.0)), "as planned it would go in leaning"
    look(data)
    for frame in (slide, lower):
        assert bottle_up(frame) @ UP > np.cos(np.radians(0.5)), "turned upright"
    assert np.allclose(lower.pos + quat_matrix(lower.quat) @ at, placed, atol=1e-6), "let go where planned"
