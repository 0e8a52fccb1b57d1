"""DexPilot retargeting (Handa et al., ICRA 2020): operator hand keypoints -> robot hand joint targets.

The cost compares task-space vectors of the operator's hand with the same vectors on the robot:
every fingertip-to-fingertip vector and every wrist-to-fingertip vector,

    C(q) = sum_i s_i || r_i(q) - t_i ||^2 + gamma || q - q_prev ||^2

with ``t_i = scale * v_i`` for a human vector ``v_i``, except for pinches. When the operator's thumb
comes within ``project_dist`` of a finger (set S1), that vector's target is projected to ``eta1``
(the robot tips touch) and weighted 200; when two fingers pinch the thumb together (set S2), the
vector between them is projected to ``eta2`` (they stay apart) and weighted 400. The projection
switches off again only beyond ``escape_dist`` (hysteresis, as in dex-retargeting's DexPilot
optimiser, from which the distances are taken). The regulariser pulls towards the previous
solution (dex-retargeting's choice) rather than towards zero (the paper's, where zero is the
open Allegro hand), since zero is not an open hand for every hand here.

The variables are the ACTUATED joints only (couplings via ``HandKinematics``), bounded by their
ranges; the solver is a damped Gauss-Newton (Levenberg-Marquardt) with an active set for the
bounds, warm-started from the previous solution. The ``dex-retargeting`` package itself is not
used: it imports torch and six without declaring them and its configs point at URDFs it does not
ship (platform facts), and b2d's hands are described in its own YAML, not URDF.

Filters: a low-pass on the keypoints before the vectors are formed and one on the joint targets
(DexPilot filters both); ``reset()`` clears them, the projections and the warm start (home).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sim.embodiment.mirror import M
from sim.embodiment.retarget_spec import MEDIAPIPE_KEYPOINTS

from .filters import LowPassFilter
from .hand_model import HandKinematics

MIRROR = np.diag(M)     # the embodiment's left/right reflection, per axis


@dataclass(frozen=True)
class DexPilotConfig:
    project_dist: float = 0.03     # m (human): a thumb-finger pinch starts below this
    escape_dist: float = 0.05      # m (human): ... and ends above this
    s2_dist: float = 0.03          # m (human): two pinching fingers closer than this are kept apart
    eta1: float = 1e-4             # m (robot): thumb-finger distance asked for in a pinch
    eta2: float = 0.03             # m (robot): distance kept between two fingers pinching together
    weight_s1: float = 200.0
    weight_s2: float = 400.0
    regularizer: float = 1e-5      # gamma (m^2 / rad^2): pull towards the previous solution
    keypoint_alpha: float = 0.6    # low-pass on the keypoints (1 = off)
    joint_alpha: float = 0.6       # low-pass on the joint targets (1 = off)
    max_iters: int = 40
    initial_damping: float = 0.1   # Levenberg-Marquardt lambda at the start of each solve
    cost_tolerance: float = 1e-10  # stop when the cost falls by less than this (m^2: 0.01 mm squared)
    relative_tolerance: float = 1e-6   # ... or by less than this fraction of it
    step_tolerance: float = 1e-5   # ... or no joint moves by more than this (rad)


def _vector_pairs(n_tips: int) -> tuple[np.ndarray, np.ndarray, int, int]:
    """(origin, task) point indices of the cost's vectors: points are 0 = wrist, 1 = thumb tip,
    2.. = the other tips. Order: S1 (thumb to each finger), S2 (finger to finger), wrist to each tip."""
    origin, task = [], []
    for i in range(1, n_tips + 1):
        for j in range(i + 1, n_tips + 1):
            origin.append(j)
            task.append(i)
    n_s1, n_s2 = n_tips - 1, (n_tips - 1) * (n_tips - 2) // 2
    for i in range(1, n_tips + 1):
        origin.append(0)
        task.append(i)
    return np.array(origin), np.array(task), n_s1, n_s2


class DexPilotRetargeter:
    """Keypoints of one operator hand -> joint targets of one robot hand (actuator order)."""

    def __init__(self, hand: str, config: DexPilotConfig = DexPilotConfig()):
        self.config = config
        self.kin = HandKinematics(hand)
        spec = self.kin.spec
        self.scale = spec.scale
        self.keypoint_ids = np.array([MEDIAPIPE_KEYPOINTS.index("wrist")] + [t.keypoint_index for t in spec.fingertips])
        self.origin, self.task, self.n_s1, self.n_s2 = _vector_pairs(len(spec.fingertips))
        # S2 vector k joins fingers a and b: it is projected only when both of their S1 vectors are
        s2 = [(self.task[k] - 2, self.origin[k] - 2) for k in range(self.n_s1, self.n_s1 + self.n_s2)]
        self.s2_fingers = np.array(s2, int).reshape(-1, 2)
        self.keypoint_filter = LowPassFilter(config.keypoint_alpha)
        self.joint_filter = LowPassFilter(config.joint_alpha)
        self.reset()

    @property
    def actuators(self) -> list[str]:
        return self.kin.actuators

    def reset(self) -> None:
        """Forget the session: filters, pinch projections and warm start (home, the open hand)."""
        self.keypoint_filter.reset()
        self.joint_filter.reset()
        self.projected = np.zeros(self.n_s1 + self.n_s2, bool)
        self.q = self.kin.home.copy()
        self.fresh = True

    # ------------------------------------------------------------------ cost
    def targets(self, keypoints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Robot-space target vectors and weights for one frame (updates the pinch projections)."""
        c = self.config
        pts = keypoints[self.keypoint_ids]
        human = pts[self.task] - pts[self.origin]
        dist = np.linalg.norm(human, axis=1)
        n1, n12 = self.n_s1, self.n_s1 + self.n_s2
        s1 = self.projected[:n1]
        s1[dist[:n1] < c.project_dist] = True
        s1[dist[:n1] > c.escape_dist] = False
        if self.n_s2:
            both = s1[self.s2_fingers[:, 0]] & s1[self.s2_fingers[:, 1]]
            self.projected[n1:n12] = both & (dist[n1:n12] <= c.s2_dist)
        targets = self.scale * human
        weights = np.ones(len(human))
        eta = np.where(np.arange(n12) < n1, c.eta1, c.eta2)
        proj = np.flatnonzero(self.projected)
        targets[proj] = human[proj] / np.maximum(dist[proj], 1e-9)[:, None] * eta[proj, None]
        weights[proj] = np.where(proj < n1, c.weight_s1, c.weight_s2)
        return targets, weights

    def _residual(self, q, targets, sqrt_w, q_ref):
        P, J = self.kin.points_and_jacobians(q)
        r_vec = (P[self.task] - P[self.origin] - targets) * sqrt_w[:, None]
        J_vec = (J[self.task] - J[self.origin]) * sqrt_w[:, None, None]
        sg = np.sqrt(self.config.regularizer)
        r = np.concatenate([r_vec.ravel(), sg * (q - q_ref)])
        Jr = np.vstack([J_vec.reshape(-1, len(q)), sg * np.eye(len(q))])
        return r, Jr

    def solve(self, targets: np.ndarray, weights: np.ndarray, q0: np.ndarray, q_ref: np.ndarray) -> tuple[np.ndarray, float]:
        """Levenberg-Marquardt within the joint ranges; joints on a bound that the gradient pushes
        against are held for the step (active set). Returns the joints and the vector cost."""
        lo, hi = self.kin.lower, self.kin.upper
        sqrt_w = np.sqrt(weights)
        q = np.clip(q0, lo, hi)
        r, Jr = self._residual(q, targets, sqrt_w, q_ref)
        cost, lam = float(r @ r), self.config.initial_damping
        for _ in range(self.config.max_iters):
            g = Jr.T @ r
            free = ~(((q <= lo) & (g > 0)) | ((q >= hi) & (g < 0)))
            H = Jr[:, free].T @ Jr[:, free]
            step = np.zeros_like(q)
            step[free] = np.linalg.solve(H + lam * (np.diag(np.diag(H)) + 1e-9 * np.eye(len(H))), -g[free])
            q_new = np.clip(q + step, lo, hi)
            r_new, J_new = self._residual(q_new, targets, sqrt_w, q_ref)
            cost_new = float(r_new @ r_new)
            if cost_new < cost:
                c = self.config
                done = (cost - cost_new < max(c.cost_tolerance, c.relative_tolerance * cost)
                        or np.max(np.abs(q_new - q)) < c.step_tolerance)
                q, r, Jr, cost, lam = q_new, r_new, J_new, cost_new, max(lam / 3, 1e-7)
                if done:
                    break
            else:
                lam *= 4
                if lam > 1e6:
                    break
        return q, cost - self.config.regularizer * float((q - q_ref) @ (q - q_ref))

    # ------------------------------------------------------------------ one frame
    def retarget(self, keypoints, side: str = "right") -> np.ndarray:
        """Joint targets (actuator order, within the joint ranges) for 21 wrist-frame keypoints of
        the operator's ``side`` hand. A left hand is mirrored onto the right-hand description: the
        mirrored robot hand takes the same joint angles (``sim/embodiment/mirror.py``)."""
        kp = np.asarray(keypoints, float)
        if kp.shape != (len(MEDIAPIPE_KEYPOINTS), 3):
            raise ValueError(f"keypoints: expected shape ({len(MEDIAPIPE_KEYPOINTS)}, 3), got {kp.shape}")
        if not np.all(np.isfinite(kp)):
            raise ValueError("keypoints: expected finite values (sanitise the stream first: StreamSanitizer)")
        if side == "left":
            kp = kp * MIRROR
        elif side != "right":
            raise ValueError(f"side: expected 'left' or 'right', got {side!r}")
        kp = self.keypoint_filter(kp)
        was_projected = self.projected.copy()
        targets, weights = self.targets(kp)
        starts = [self.q]
        if self.fresh or not np.array_equal(was_projected, self.projected):
            # no warm start yet, or a pinch began or ended (the targets jump): also try home and
            # mid-range, so the thumb does not stay in a local minimum on the way to the pinch
            starts += [self.kin.home, self.kin.mid]
        solutions = [self.solve(targets, weights, q0, self.q) for q0 in starts]
        self.q = min(solutions, key=lambda s: s[1])[0]
        self.fresh = False
        return np.clip(self.joint_filter(self.q), self.kin.lower, self.kin.upper)
