"""Arm kinematics with Pinocchio, built from the same arm description, mount and hand tool
transform as the MuJoCo model (no URDF file).

The model is the arm chain; the hand is a rigid payload lumped on the last link (used only for the
inertia estimates behind the servo gains). ``fk`` and ``ik`` work on the wrist site (palm-centre grasp
frame) in WORLD coordinates.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from .description import KEEP_SIGN_MARGIN_RAD, ArmDescription, HandDescription, Transform, mat_to_quat, quat_to_mat
from .mirror import side_links, side_transform

POS_TOL_M = 2e-3
ROT_TOL_RAD = math.radians(2.0)
AGAIN_CLOSER = 0.5      # ik_again_from: a miss solved from home must come this much closer to be kept


def axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    return pin.exp3(np.asarray(axis, float) * angle)


def hand_link_poses(hand: HandDescription, q: dict[str, float] | None = None, side: str = "right") -> dict[str, Transform]:
    """Pose of every hand link in the hand base frame for joint angles ``q`` (default 0)."""
    q = q or {}
    poses: dict[str, Transform] = {}
    for link in side_links(hand.links, side):
        parent = poses[link.parent] if link.parent else Transform.identity()
        T = parent @ link.origin
        for j in link.joints:
            T = T @ Transform(np.zeros(3), axis_rotation(j.axis, q.get(j.name, 0.0)))
        poses[link.name] = T
    return poses


def hand_payload(hand: HandDescription) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass, com and 3x3 inertia about the com of the whole hand at q = 0, hand base frame."""
    poses = hand_link_poses(hand)
    m_tot, c_sum = 0.0, np.zeros(3)
    items = []
    for link in hand.links:
        T = poses[link.name]
        c = T.pos + T.rot @ link.inertial.com
        I = T.rot @ np.diag(link.inertial.inertia) @ T.rot.T
        items.append((link.inertial.mass, c, I))
        m_tot += link.inertial.mass
        c_sum += link.inertial.mass * c
    com = c_sum / m_tot
    I_tot = np.zeros((3, 3))
    for m, c, I in items:
        r = c - com
        I_tot += I + m * ((r @ r) * np.eye(3) - np.outer(r, r))
    return m_tot, com, I_tot


def _se3(T: Transform) -> pin.SE3:
    return pin.SE3(np.ascontiguousarray(T.rot), np.ascontiguousarray(T.pos))


@dataclass
class IKResult:
    q: np.ndarray
    success: bool
    pos_err_m: float
    rot_err_rad: float
    iterations: int
    from_home: bool = False     # solved again from home after the warm start missed (ArmKinematics.ik_again_from)

    @property
    def miss(self) -> float:
        """How far off the pose is in units of the success tolerances (<= 1: success)."""
        return max(self.pos_err_m / POS_TOL_M, self.rot_err_rad / ROT_TOL_RAD)


class ArmKinematics:
    """Forward / inverse kinematics of one side's arm up to the wrist site, world frame."""

    def __init__(self, arm: ArmDescription, mount: Transform, hand: HandDescription, side: str):
        self.arm = arm
        self.side = side
        model = pin.Model()
        model.name = f"{side}_{arm.name}"
        base = arm.links[0]
        parent_id = 0
        placement = mount
        # the fixed base link sits on the universe joint
        model.appendBodyToJoint(0, pin.Inertia(base.inertial.mass, base.inertial.com, np.diag(base.inertial.inertia)),
                                _se3(mount))
        for link in arm.links[1:]:
            (j,) = link.joints
            placement = link.origin if parent_id else mount @ link.origin
            jid = model.addJoint(
                parent_id, pin.JointModelRevoluteUnaligned(np.asarray(j.axis, float)), _se3(placement), j.name,
                np.array([j.effort]), np.array([j.velocity]), np.array([j.range[0]]), np.array([j.range[1]]),
            )
            model.appendBodyToJoint(jid, pin.Inertia(link.inertial.mass, link.inertial.com, np.diag(link.inertial.inertia)),
                                    pin.SE3.Identity())
            parent_id = jid
        self.last_joint = parent_id
        hand_base = arm.flange @ side_transform(hand.mount, side)
        self.tool = hand_base @ side_transform(hand.wrist_site, side)      # last link -> wrist site
        m, com, I = hand_payload(hand)
        model.appendBodyToJoint(parent_id, pin.Inertia(m, com, I), _se3(hand_base))
        self.frame_id = model.addFrame(pin.Frame("wrist_site", parent_id, 0, _se3(self.tool), pin.FrameType.OP_FRAME))
        for k in range(model.nq):
            model.armature[k] = arm.joints[k].armature
        self.model = model
        self.data = model.createData()
        self.lower = model.lowerPositionLimit.copy()
        self.upper = model.upperPositionLimit.copy()
        self.joint_names = [j.name for j in arm.joints]
        # the IK's bounds: the joint limits, narrowed to the home seed's branch of `ik_keep_sign` joints
        self.ik_lower, self.ik_upper = self.lower.copy(), self.upper.copy()
        for name in arm.ik_keep_sign:
            k = self.joint_names.index(name)
            if arm.home_seed[side][k] > 0:
                self.ik_lower[k] = max(self.ik_lower[k], KEEP_SIGN_MARGIN_RAD)
            else:
                self.ik_upper[k] = min(self.ik_upper[k], -KEEP_SIGN_MARGIN_RAD)

    @property
    def nq(self) -> int:
        return self.model.nq

    def fk_se3(self, q: np.ndarray) -> pin.SE3:
        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, float))
        return self.data.oMf[self.frame_id].copy()

    def fk(self, q_arm) -> tuple[np.ndarray, np.ndarray]:
        """Wrist-site position (3,) and orientation quaternion (w, x, y, z) in world."""
        T = self.fk_se3(q_arm)
        return T.translation.copy(), mat_to_quat(T.rotation)

    def joint_space_inertia(self, q: np.ndarray) -> np.ndarray:
        return pin.crba(self.model, self.data, np.asarray(q, float))

    def ik(self, target_pos, target_quat_wxyz, q_init, max_iters: int = 200,
           damping: float = 1e-3, pos_tol: float = 1e-5, rot_tol: float = 1e-5) -> IKResult:
        """Damped least squares CLIK on the wrist site; joints clipped to their limits (and the arm's
        `ik_keep_sign` branches) each step.
        Iterates to a tight tolerance; ``success`` means within 2 mm and 2 degrees."""
        target = pin.SE3(quat_to_mat(np.asarray(target_quat_wxyz, float) / np.linalg.norm(target_quat_wxyz)),
                         np.asarray(target_pos, float))
        q = np.clip(np.asarray(q_init, float).copy(), self.ik_lower, self.ik_upper)
        it = 0
        pe = re = float("inf")
        for it in range(1, max_iters + 1):
            T = self.fk_se3(q)
            e_pos = target.translation - T.translation
            e_rot = pin.log3(target.rotation @ T.rotation.T)
            pe, re = float(np.linalg.norm(e_pos)), float(np.linalg.norm(e_rot))
            if pe < pos_tol and re < rot_tol:
                break
            J = pin.computeFrameJacobian(self.model, self.data, q, self.frame_id, pin.LOCAL_WORLD_ALIGNED)
            e = np.concatenate([e_pos, e_rot])
            lam2 = damping ** 2 + 1e-2 * min(1.0, pe + re) ** 2
            dq = J.T @ np.linalg.solve(J @ J.T + lam2 * np.eye(6), e)
            n = np.linalg.norm(dq)
            if n > 0.5:
                dq *= 0.5 / n
            q = np.clip(q + dq, self.ik_lower, self.ik_upper)
        T = self.fk_se3(q)
        pe = float(np.linalg.norm(target.translation - T.translation))
        re = float(np.linalg.norm(pin.log3(target.rotation @ T.rotation.T)))
        return IKResult(q=q, success=bool(pe <= POS_TOL_M and re <= ROT_TOL_RAD), pos_err_m=pe,
                        rot_err_rad=re, iterations=it)

    def ik_again_from(self, result: IKResult, target_pos, target_quat_wxyz, q_seed, max_iters: int = 200) -> IKResult:
        """``result`` (a warm-started ``ik`` of the same target) if it succeeded; else the target solved
        again from ``q_seed`` (the arm's home), kept if it reaches the pose or comes at least
        1 / AGAIN_CLOSER times closer (``IKResult.miss``). A warm start keeps the arm on its current
        branch, which a smooth path wants, but once a path has dragged the arm against its joint limits
        the warm start may never leave that branch again (the xArm7 tracking condiment_box_loading's
        plan: up to 115 cm off, 447 steps more than 1 cm off; with this, 8 cm and 10 steps); home is
        where every path starts. A pose out of reach from both stays with the warm start: a marginally
        closer solve from home would only swing the arm over to another branch. Only a miss is solved
        again, so a path the warm start follows is unchanged bit for bit."""
        if result.success:
            return result
        again = self.ik(target_pos, target_quat_wxyz, q_seed, max_iters=max_iters)
        if again.success or again.miss < AGAIN_CLOSER * result.miss:
            return replace(again, from_home=True)
        return result

    def ik_tracking(self, target_pos, target_quat_wxyz, q_warm, q_home, max_iters: int = 200) -> IKResult:
        """A pose along a path: solved warm from ``q_warm`` (the last solve: it keeps the arm on its
        branch), and again from ``q_home`` where that misses (``ik_again_from``)."""
        warm = self.ik(target_pos, target_quat_wxyz, q_warm, max_iters=max_iters)
        return self.ik_again_from(warm, target_pos, target_quat_wxyz, q_home, max_iters=max_iters)
