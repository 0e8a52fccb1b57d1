"""How far a planned wrist pose runs a hand into its own arm, which the arm's IK does not see: turned to stand
a marker up in the pen cup, the Schunk's thumb base went 4-5 cm into the UR5's forearm
(stationery_category_sorting), and in physics the wrist stopped 10 cm short of the cup. Also how deep any two sets
of bodies meet with an arm at given joints (contact_depth: park.py's check of the other arm against a resting hand)."""

from __future__ import annotations

import mujoco
import numpy as np

# deeper than this a planned pose runs the hand into its own arm (the RM65+Revo2's poses standing the marker up: none)
OWN_ARM_DEPTH_M = 0.005


def into_own_arm(op, data: mujoco.MjData, side: dict, poses, q_seed: np.ndarray) -> float:
    """How deep (metres) ``side``'s hand goes into its own arm at the wrist poses ``poses`` ((pos, quat) each, the
    arm's IK warm-started along them from ``q_seed``), the rest of the scene as in ``data``."""
    model, lay = op.scene.model, op.scene.layout.sides[side["name"]]
    hand = {model.body(b).id for b in lay.hand_bodies}
    arm = {model.body(b).id for b in lay.arm_bodies}
    return _deepest(op, data, side, poses, q_seed, hand, arm)


def arm_into_scene(op, data: mujoco.MjData, side: dict, poses, q_seed: np.ndarray) -> float:
    """How deep (metres) ``side``'s arm (not its hand) goes into anything not a robot (the objects, the table) at the
    wrist poses ``poses``, as into_own_arm: taking the RH5DG2's pinch, the UR5's wrist_1 link pressed on the pen cup's
    rim 25 cm from the hand (stationery_category_sorting) and held the tips over the marker."""
    model, layout = op.scene.model, op.scene.layout
    arm = {model.body(b).id for b in layout.sides[side["name"]].arm_bodies}
    robots = {model.body(b).id for lay in layout.sides.values() for b in (*lay.arm_bodies, *lay.hand_bodies)}
    return _deepest(op, data, side, poses, q_seed, arm, set(range(model.nbody)) - robots)


def _deepest(op, data: mujoco.MjData, side: dict, poses, q_seed: np.ndarray, these: set, those: set) -> float:
    """The deepest contact between bodies ``these`` and ``those`` with ``side``'s arm at each of ``poses``."""
    probe = mujoco.MjData(op.scene.model)
    q, deepest = q_seed, 0.0
    for pos, quat in poses:
        q = side["kin"].ik(pos, quat, q).q
        deepest = max(deepest, contact_depth(op, data, probe, side["name"], q, these, those))
    return deepest


def contact_depth(op, data: mujoco.MjData, probe: mujoco.MjData, side_name: str, q: np.ndarray, these: set,
                  those: set) -> float:
    """How deep (metres, 0 if apart) bodies ``these`` and ``those`` meet with side ``side_name``'s arm joints at
    ``q`` and the rest of the scene as in ``data`` (``probe``: scratch data for the check)."""
    model = op.scene.model
    joints = [model.joint(j).qposadr[0] for j in op.scene.layout.sides[side_name].arm_joints]
    probe.qpos[:] = data.qpos
    probe.qpos[joints] = q
    mujoco.mj_forward(model, probe)
    deepest = 0.0
    for c in probe.contact[:probe.ncon]:
        a, b = model.geom_bodyid[c.geom1], model.geom_bodyid[c.geom2]
        if a in these and b in those or b in these and a in those:
            deepest = max(deepest, -float(c.dist))
    return deepest
