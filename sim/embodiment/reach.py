"""How far an arm reaches from its home wrist pose, measured with its own kinematics.

The arm file's ``reach.home_radius_m`` is the radius around the bimanual home wrist pose out to which
palm-down wrist poses (yawed by each of ``YAWS_RAD`` about the fingers) are reached by the IK from the
home joint angles, in every direction over the table in front of the robot (forward and/or down).
Per direction it is the farthest distance, in ``step_m`` steps up to ``MAX_RADIUS_M``, at which every
yaw is still reached; the reach is the shortest of these over directions, both sides and the
embodiments that use the arm, so tests and scripted plans can ask it of any arm without a per-arm
special case. (Nearer poses are reached too, except where a home pose rests on a joint limit and the
IK stalls; the embodiment tests' targets check that.)

    python -m sim.embodiment.reach            # prints the measured radius of every arm
"""

from __future__ import annotations

import math

import numpy as np

from .builder import SIDES, home_arm_angles
from .description import arm_names, embodiment_names, load_embodiment, mat_to_quat, quat_to_mat
from .kinematics import ArmKinematics
from .mirror import mirror_vec

YAWS_RAD = (-0.3, 0.0, 0.3)
MAX_RADIUS_M = 0.5


def work_directions() -> np.ndarray:
    """Unit directions over the table in front (world +y forward, -z down): a 5 x 3 x 3 grid of
    x in [-1, 1], y in [0, 1], z in [-1, 0], without the purely sideways ones (y = z = 0)."""
    out = []
    for x in (-1.0, -0.5, 0.0, 0.5, 1.0):
        for y in (0.0, 0.5, 1.0):
            for z in (-1.0, -0.5, 0.0):
                if (y, z) != (0.0, 0.0):
                    d = np.array([x, y, z])
                    out.append(d / np.linalg.norm(d))
    return np.array(out)


def _yawed(R: np.ndarray, yaw: float) -> np.ndarray:
    return R @ quat_to_mat([math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)])


def reach_along(kin: ArmKinematics, q_home: np.ndarray, p0: np.ndarray, R0: np.ndarray, d: np.ndarray,
                step_m: float) -> float:
    """Farthest r (a multiple of step_m, up to MAX_RADIUS_M) at which the pose p0 + r d is reached
    from the home joint angles for every yaw; 0 if none is."""
    best = 0.0
    for k in range(1, int(round(MAX_RADIUS_M / step_m)) + 1):
        r = k * step_m
        if all(kin.ik(p0 + r * d, mat_to_quat(_yawed(R0, yaw)), q_home).success for yaw in YAWS_RAD):
            best = r
    return best


def embodiment_reach(name: str, step_m: float = 0.01) -> float:
    """Shortest reliable reach over both sides and every work direction of one embodiment."""
    emb = load_embodiment(name)
    homes = dict(zip(SIDES, home_arm_angles(emb.name)))
    best = MAX_RADIUS_M
    for side in SIDES:
        kin = ArmKinematics(emb.arm, emb.mounts[side], emb.hand, side)
        q_home = np.array(homes[side])
        p0, q0 = kin.fk(q_home)
        R0 = quat_to_mat(q0)
        for d in work_directions():
            d_side = d if side == "right" else mirror_vec(d)
            best = min(best, reach_along(kin, q_home, p0, R0, d_side, step_m))
    return best


def arm_reach(arm: str, step_m: float = 0.01) -> dict[str, float]:
    """Reach of ``arm`` in every embodiment that uses it (embodiment -> metres)."""
    return {n: embodiment_reach(n, step_m) for n in embodiment_names() if load_embodiment(n).arm.name == arm}


if __name__ == "__main__":
    for a in arm_names():
        per = arm_reach(a)
        print(f"{a:10s} home_radius_m {min(per.values()):.2f}  " + "  ".join(f"{k} {v:.2f}" for k, v in per.items()))
