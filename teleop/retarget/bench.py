"""Retargeting speed per hand: ms per DexPilot step on a generated operator session.

    python -m teleop.retarget.bench           # prints the table, returns the figures

The session is the same for every hand: an open hand closing into a power grasp and opening again,
then a thumb-index pinch (60 Hz frames from ``human_hand``), retargeted frame by frame with the
filters and warm start as in a live session. Baselines measured in the same run, per hand:

* ``fk_jac_ms``: one forward-kinematics + Jacobian evaluation (the floor under one solver iteration);
* ``scipy_ms``: ``scipy.optimize.least_squares`` (trust-region reflective, bounds, analytic
  Jacobian) on the same frames' cost from the same warm start: what an off-the-shelf bounded
  least-squares solver costs. ``worst_cost_ratio_vs_scipy`` compares the answers: our cost over
  scipy's on the worst frame (1.0 = as good; below 1 = better).
"""

from __future__ import annotations

import time

import numpy as np
from scipy.optimize import least_squares

from sim.embodiment.description import hand_names
from teleop.streams.human_hand import open_hand, pinch, power_grasp

from .dexpilot import DexPilotRetargeter


def session_keypoints(frames: int = 120) -> list[np.ndarray]:
    """Open -> power grasp -> open -> pinch, ``frames`` keypoint sets of the right hand."""
    out = []
    for k in range(frames):
        s = k / max(frames - 1, 1)
        if s < 0.6:
            out.append(power_grasp(np.sin(np.pi * s / 0.6)))
        else:
            w = min(1.0, (s - 0.6) / 0.3)
            out.append((1 - w) * open_hand() + w * pinch("index"))
    return out


def _scipy_step(rt: DexPilotRetargeter, targets, weights, q0) -> np.ndarray:
    sqrt_w = np.sqrt(weights)
    lo, hi = rt.kin.lower, rt.kin.upper
    x0 = np.clip(q0, lo + 1e-9, hi - 1e-9)     # least_squares wants a strictly feasible start
    result = least_squares(lambda q: rt._residual(q, targets, sqrt_w, q0)[0], x0,
                           jac=lambda q: rt._residual(q, targets, sqrt_w, q0)[1], bounds=(lo, hi), method="trf")
    return result.x


def bench_hand(hand: str, frames: int = 120) -> dict:
    keypoints = session_keypoints(frames)
    rt = DexPilotRetargeter(hand)
    t0 = time.perf_counter()
    for kp in keypoints:
        rt.retarget(kp)
    ours = (time.perf_counter() - t0) / frames

    kin = rt.kin
    t0 = time.perf_counter()
    for _ in range(frames):
        kin.points_and_jacobians(kin.home)
    fk = (time.perf_counter() - t0) / frames

    ref = DexPilotRetargeter(hand)
    q = ref.kin.home.copy()
    elapsed, worst_ratio = 0.0, 0.0
    for kp in keypoints:
        # same filtered keypoints and pinch projections as the live retargeter sees
        targets, weights = ref.targets(ref.keypoint_filter(kp))
        t0 = time.perf_counter()
        q_ref = _scipy_step(ref, targets, weights, q)
        elapsed += time.perf_counter() - t0
        q_ours, _ = ref.solve(targets, weights, q, q)
        sqrt_w = np.sqrt(weights)
        costs = [float(np.sum(ref._residual(x, targets, sqrt_w, q)[0] ** 2)) for x in (q_ours, q_ref)]
        worst_ratio = max(worst_ratio, costs[0] / max(costs[1], 1e-15))
        q = q_ref
    return {"dof": kin.dof, "fingers": len(kin.spec.fingertips), "ms_per_step": round(ours * 1e3, 3),
            "fk_jac_ms": round(fk * 1e3, 4), "scipy_ms": round(elapsed / frames * 1e3, 3),
            "worst_cost_ratio_vs_scipy": round(worst_ratio, 3)}


def run_bench(hands: list[str] | None = None, frames: int = 120, echo: bool = True) -> dict:
    """ms per retarget step for each hand (plus the baselines above); prints a table."""
    figures = {hand: bench_hand(hand, frames) for hand in (hands or hand_names())}
    if echo:
        print(f"{'hand':12s} {'dof':>4s} {'ms/step':>8s} {'fk+jac ms':>10s} {'scipy ms':>9s} {'cost/scipy':>11s}")
        for hand, f in figures.items():
            print(f"{hand:12s} {f['dof']:4d} {f['ms_per_step']:8.3f} {f['fk_jac_ms']:10.4f} {f['scipy_ms']:9.3f} "
                  f"{f['worst_cost_ratio_vs_scipy']:11.3f}")
    return {"frames": frames, "hands": figures}


if __name__ == "__main__":
    run_bench()
