"""`turn`'s opt-in `palm_look`: as the fingertips let go of a lid for the palm, the operator looks where
the lid is and the palm's keyframes turn about the hinge with it. On the UR5s the lid, let go below
vertical, falls back at that handoff and the palm planned for it higher lands on its edge: the lid falls
shut; with the look the palm comes at it where it fell and pushes it open onto its stop."""

import mujoco
import numpy as np
import yaml

from sim import physics
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task, parse_task
from teleop.demos import DEFAULT_OPERATOR, OPERATORS
from teleop.plan_steps.turn import ARC_STEP_RAD, LOOKS, Hinge
from teleop.recorder import home
from plan_runs import home_and_plan

TASK, LID = "toilet_lid_cleaner_pour", "toilet/lid"
OPEN = {"hand": "left", "turn": LID, "to": 1.6, "palm_from": 1.2}    # the task file's opening step


def _task(tmp_path, step: dict):
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    raw["demo_plan"] = [step]
    return parse_task(raw, tmp_path / "toilet.yaml")


def _angle_about(link: Hinge, p: np.ndarray) -> float:
    """Where point ``p`` lies round the hinge axis (rad, from an arbitrary zero)."""
    r = link.radial_vec(p)
    ref = link.radial_vec(link.handle)
    return float(np.arctan2(np.cross(ref, r) @ link.axis, ref @ r))


def test_palm_look_turns_the_palm_keyframes_with_the_lid(tmp_path):
    scene = demonstration_scene(_task(tmp_path, {**OPEN, "palm_look": True}), "xarm7_leap")
    data, op = home_and_plan(scene)
    link = Hinge(scene.model, data, LID)
    side = op.sides["left"]
    frames = side["timeline"].frames
    looks = [adjust for _, adjust in side["looks"] if adjust.__name__ == "look_at_link"]
    assert len(looks) == LOOKS
    before = [(f.pos.copy(), f.quat.copy()) for f in frames]
    # the palm was planned from the first arc angle at or past palm_from; the lid fell back to 0.9 rad
    arc = np.linspace(link.angle, OPEN["to"], int(np.ceil((OPEN["to"] - link.angle) / ARC_STEP_RAD)) + 1)
    fell = float(arc[arc >= OPEN["palm_from"] - 1e-9][0]) - 0.9
    data.qpos[scene.joint_qpos_adr[LID]] = 0.9
    mujoco.mj_forward(scene.model, data)
    looks[0](data)
    moved = [i for i, f in enumerate(frames) if not np.allclose(f.pos, before[i][0])]
    assert moved, "the look moved no keyframe"
    first = moved[0]
    # the palm's first keyframe turned with the lid about its hinge by as much as the lid fell, kept
    # its distance from the hinge, and its rotation turned by as much
    turned = _angle_about(link, frames[first].pos) - _angle_about(link, before[first][0])
    assert abs(abs(turned) - fell) < 1e-6
    assert np.isclose(np.linalg.norm(link.radial_vec(frames[first].pos)),
                      np.linalg.norm(link.radial_vec(before[first][0])))
    R0, R1 = np.zeros(9), np.zeros(9)
    mujoco.mju_quat2Mat(R0, before[first][1])
    mujoco.mju_quat2Mat(R1, frames[first].quat)
    rel = R1.reshape(3, 3) @ R0.reshape(3, 3).T
    assert np.isclose(np.arccos(np.clip((np.trace(rel) - 1) / 2, -1, 1)), fell)
    # the push still ends where planned: the lid at the turn's target
    last = max(moved)
    assert np.allclose(frames[last + 1].pos, before[last + 1][0])
    assert all(np.allclose(f.pos, b[0]) for f, b in zip(frames[:first], before[:first]))


def test_without_palm_look_no_look_and_one_frame_fewer(tmp_path):
    scene = demonstration_scene(_task(tmp_path, OPEN), "xarm7_leap")
    _, op = home_and_plan(scene)
    scene_look = demonstration_scene(_task(tmp_path, {**OPEN, "palm_look": True}), "xarm7_leap")
    _, op_look = home_and_plan(scene_look)
    assert not [a for _, a in op.sides["left"]["looks"] if a.__name__ == "look_at_link"]
    # with the look the hand moves in under the face in a keyframe of its own after backing off
    assert len(op_look.sides["left"]["timeline"].frames) == len(op.sides["left"]["timeline"].frames) + 1


def _lid_after(task) -> float:
    scene = demonstration_scene(task, "ur5_rh56dfx")
    data = home(scene)
    op = OPERATORS[DEFAULT_OPERATOR]()
    op.reset(scene, data)
    for step in range(op.plan.length):
        physics.step_control(scene.model, data, op.act(step, data))
    return float(data.qpos[scene.joint_qpos_adr[LID]])


def test_palm_look_opens_the_lid_a_ur5_drops_at_the_handoff(tmp_path):
    assert _lid_after(_task(tmp_path, OPEN)) < 0.1
    assert _lid_after(_task(tmp_path, {**OPEN, "palm_look": True})) > 1.6
