"""Forward kinematics of one robot hand over its ACTUATED joints, for retargeting.

A kinematics-only MuJoCo model is built from the hand description (bodies, hinge joints, the
retarget points as sites; the hand base is the world frame). Coupled (mimic) joints follow their
master through the hand file's polynomial, as the joint equalities do in simulation, so the
optimiser only ever moves what a servo can move: ``points(q)`` and ``jacobians(q)`` take the
actuated joint vector, in the order of the hand's actuators (= the order of its control targets).
"""

from __future__ import annotations

import mujoco
import numpy as np

from sim.embodiment.description import DescriptionError, HandDescription, coupled_position, coupled_slope, load_hand
from sim.embodiment.retarget_spec import RetargetSpec, load_retarget_spec


def _build_model(hand: HandDescription, spec: RetargetSpec) -> mujoco.MjModel:
    mj = mujoco.MjSpec()
    mj.compiler.degree = False
    bodies = {}
    for link in hand.links:
        parent = bodies[link.parent] if link.parent else mj.worldbody
        body = parent.add_body(name=link.name, pos=link.origin.pos, quat=link.origin.quat)
        # kinematics only, but MuJoCo wants moving bodies to have mass
        body.explicitinertial = True
        body.mass = link.inertial.mass
        body.ipos = link.inertial.com
        body.inertia = np.maximum(link.inertial.inertia, 1e-9)
        for j in link.joints:
            body.add_joint(name=j.name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=j.axis)
        bodies[link.name] = body
    bodies[spec.wrist.body].add_site(name="retarget_wrist", pos=spec.wrist.pos)
    for tip in spec.fingertips:
        bodies[tip.point.body].add_site(name=f"retarget_{tip.finger}", pos=tip.point.pos)
    return mj.compile()


class HandKinematics:
    """Retarget points (wrist first, then the fingertips in the spec's order) of one right hand."""

    def __init__(self, hand_name: str):
        self.hand = load_hand(hand_name)
        self.spec = load_retarget_spec(hand_name)
        self.model = _build_model(self.hand, self.spec)
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.actuators = [a.name for a in self.hand.actuators]
        self.act_qadr = np.array([m.joint(a.joint).qposadr[0] for a in self.hand.actuators])
        ranges = np.array([self.hand.joint(a.joint).range for a in self.hand.actuators], float)
        self.lower, self.upper = ranges[:, 0].copy(), ranges[:, 1].copy()
        self.mid = (self.lower + self.upper) / 2
        self.home = np.clip([self.hand.home.get(a.joint, 0.0) for a in self.hand.actuators], self.lower, self.upper)
        act_of_joint = {a.joint: i for i, a in enumerate(self.hand.actuators)}
        for c in self.hand.couplings:
            if c.master not in act_of_joint:
                raise DescriptionError(f"{self.hand.path}: field 'couplings': master {c.master!r} of {c.joint!r} "
                                       f"is not actuated (retargeting needs couplings on actuated joints)")
        # the couplings as arrays, one row per follower: its qpos address, its master's actuator index,
        # its polynomial's coefficients (constant first) and its range
        couplings = self.hand.couplings
        self._follower = np.array([m.joint(c.joint).qposadr[0] for c in couplings], int)
        self._master = np.array([act_of_joint[c.master] for c in couplings], int)
        degree = max((len(c.polycoef) for c in couplings), default=1)
        self._coef = np.zeros((len(couplings), degree))
        for i, c in enumerate(couplings):
            self._coef[i, : len(c.polycoef)] = c.polycoef
        ranges = np.array([self.hand.joint(c.joint).range for c in couplings], float).reshape(-1, 2)
        self._follower_lo, self._follower_hi = ranges[:, 0], ranges[:, 1]
        self.site_ids = np.array([m.site("retarget_wrist").id] + [m.site(f"retarget_{t.finger}").id
                                                                   for t in self.spec.fingertips])
        self._jacp = np.zeros((3, m.nv))
        self._dfull = np.zeros((m.nv, len(self.actuators)))   # d qpos / d q_actuated (hinges only: nq = nv)
        self._dfull[self.act_qadr, np.arange(len(self.actuators))] = 1.0

    @property
    def dof(self) -> int:
        return len(self.actuators)

    def _set(self, q: np.ndarray) -> None:
        qpos = self.data.qpos
        qpos[self.act_qadr] = q
        if len(self._follower):
            x = q[self._master]         # every follower's polynomial at once
            value, slope = coupled_position(self._coef, x), coupled_slope(self._coef, x)
            lo, hi = self._follower_lo, self._follower_hi
            qpos[self._follower] = np.minimum(np.maximum(value, lo), hi)
            # the chain rule through the coupling; zero where the follower sits on its limit
            self._dfull[self._follower, self._master] = np.where((value <= lo) | (value >= hi), 0.0, slope)
        mujoco.mj_kinematics(self.model, self.data)

    def points(self, q: np.ndarray) -> np.ndarray:
        """(1 + fingers, 3) wrist point and fingertips in the hand-base frame."""
        self._set(np.asarray(q, float))
        return self.data.site_xpos[self.site_ids].copy()

    def points_and_jacobians(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Points (P, 3) and their Jacobians (P, 3, dof) with respect to the actuated joints."""
        self._set(np.asarray(q, float))
        mujoco.mj_comPos(self.model, self.data)      # mj_jac reads the com-based dof frames
        J = np.empty((len(self.site_ids), 3, self.dof))
        for k, sid in enumerate(self.site_ids):
            mujoco.mj_jacSite(self.model, self.data, self._jacp, None, int(sid))
            J[k] = self._jacp @ self._dfull
        return self.data.site_xpos[self.site_ids].copy(), J
