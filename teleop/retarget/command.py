"""Operator stream -> one absolute joint-position command for the whole bimanual robot.

Per side, the hand's keypoints go through DexPilot retargeting (hand actuator targets) and the
wrist pose through the arm's Pinocchio CLIK (``sim/embodiment/kinematics.py``); both are written
into one control vector in the model's actuator order (arm then hand per side, as the builder
lays them out), the rest of the robot holding home.

Wrist anchors: the first valid wrist pose after ``reset`` is the operator's anchor and the robot
hand's home pose is the robot's. Afterwards the robot hand base follows the operator's wrist
motion relative to the anchor, expressed in the hand's own frame::

    T_base = T_base_home @ (T_wrist_anchor^-1 @ T_wrist)      (translation times ``translation_scale``)

so the tracker's world frame needs no calibration. The arm IK then targets the wrist site, which
sits at a fixed offset on the hand base. A pose the arm cannot reach (IK outside 2 mm / 2 degrees
even with a long solve) holds the last arm target and flags the step ``UNREACHABLE``.

``reset()`` is called before an episode starts or is saved: it returns the home command and
clears the filters, pinch projections, IK warm starts and wrist anchors.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np

from sim.embodiment.builder import RobotLayout
from sim.embodiment.description import Transform, load_embodiment, quat_to_mat
from sim.embodiment.kinematics import ArmKinematics
from sim.embodiment.mirror import side_transform
from teleop.streams.frame import SIDES
from teleop.streams.sanitizer import SanitizedStep, StepFlag

from .dexpilot import DexPilotConfig, DexPilotRetargeter

FAST_IK_ITERS = 30      # warm-started IK while the operator moves smoothly
SLOW_IK_ITERS = 300     # a second, longer try before a pose is called unreachable


@dataclass(frozen=True)
class Command:
    ctrl: np.ndarray             # (nu,) absolute joint targets, model actuator order
    flags: StepFlag
    reasons: tuple[str, ...]


@dataclass
class _Side:
    name: str
    arm_ids: np.ndarray
    hand_ids: np.ndarray
    kin: ArmKinematics
    retargeter: DexPilotRetargeter
    site_in_base: Transform      # wrist site in the hand-base frame (mirrored on the left)
    home_arm: np.ndarray
    home_hand: np.ndarray
    base_home: Transform = field(init=False)
    arm_q: np.ndarray = field(init=False)
    hand_q: np.ndarray = field(init=False)
    anchor: Transform | None = None


class TeleopCommander:
    def __init__(self, model: mujoco.MjModel, layout: RobotLayout, translation_scale: float = 1.0,
                 retarget_config: DexPilotConfig = DexPilotConfig()):
        hand = load_embodiment(layout.embodiment).hand
        self.translation_scale = float(translation_scale)
        act_ids = layout.actuator_ids(model)
        self.home_ctrl = np.zeros(model.nu)
        self.home_ctrl[act_ids] = layout.home_ctrl
        self.sides: dict[str, _Side] = {}
        for side in SIDES:
            lay = layout.sides[side]
            arm_ids = np.array([model.actuator(a).id for a in lay.arm_actuators])
            hand_ids = np.array([model.actuator(a).id for a in lay.hand_actuators])
            retargeter = DexPilotRetargeter(hand.name, retarget_config)
            expected = [f"{side}_{a}" for a in retargeter.actuators]
            if list(lay.hand_actuators) != expected:
                raise ValueError(f"{hand.path}: hand actuators in the model {lay.hand_actuators} do not match "
                                 f"the retargeter's order {expected}")
            s = _Side(side, arm_ids, hand_ids, layout.arm_kinematics(side), retargeter,
                      side_transform(hand.wrist_site, side), self.home_ctrl[arm_ids].copy(),
                      self.home_ctrl[hand_ids].copy())
            T = s.kin.fk_se3(s.home_arm)
            s.base_home = Transform(T.translation.copy(), T.rotation.copy()) @ s.site_in_base.inverse()
            self.sides[side] = s
        self.reset()

    def reset(self) -> np.ndarray:
        """Home command; filters, projections, warm starts and wrist anchors forgotten."""
        for s in self.sides.values():
            s.retargeter.reset()
            s.arm_q, s.hand_q, s.anchor = s.home_arm.copy(), s.home_hand.copy(), None
        return self.home_ctrl.copy()

    def wrist_site_target(self, side: str, wrist_pos, wrist_quat) -> Transform:
        """Where the robot's wrist site should go for an operator wrist pose (anchoring on the first)."""
        s = self.sides[side]
        T = Transform(np.asarray(wrist_pos, float), quat_to_mat(np.asarray(wrist_quat, float)))
        if s.anchor is None:
            s.anchor = T
        delta = s.anchor.inverse() @ T
        delta = Transform(delta.pos * self.translation_scale, delta.rot)
        return s.base_home @ delta @ s.site_in_base

    def _arm(self, s: _Side, target: Transform) -> tuple[bool, str]:
        quat = target.quat
        result = s.kin.ik(target.pos, quat, s.arm_q, max_iters=FAST_IK_ITERS)
        if not result.success:      # continue where the fast try stopped: the same 300 iterations in all
            result = s.kin.ik(target.pos, quat, result.q, max_iters=SLOW_IK_ITERS - FAST_IK_ITERS)
        # the warm start may have lost the arm's branch on the way: the same pose from home
        result = s.kin.ik_again_from(result, target.pos, quat, s.home_arm, max_iters=SLOW_IK_ITERS)
        if not result.success:
            return False, (f"{s.name} wrist: unreachable (IK {result.pos_err_m * 1000:.1f} mm / "
                           f"{np.degrees(result.rot_err_rad):.1f} deg off); last arm target held")
        s.arm_q = result.q
        return True, ""

    def command(self, step: SanitizedStep) -> Command:
        flags, reasons = step.flags, list(step.reasons)
        frame = step.frame
        ctrl = self.home_ctrl.copy()
        for i, side in enumerate(SIDES):
            s = self.sides[side]
            if step.fresh_keypoints[i]:
                s.hand_q = s.retargeter.retarget(frame.keypoints[i], side)
            if step.fresh_wrist[i]:
                ok, why = self._arm(s, self.wrist_site_target(side, frame.wrist_pos[i], frame.wrist_quat[i]))
                if not ok:
                    flags |= StepFlag.UNREACHABLE
                    reasons.append(why)
            ctrl[s.arm_ids] = s.arm_q
            ctrl[s.hand_ids] = s.hand_q
        return Command(ctrl, flags, tuple(reasons))
