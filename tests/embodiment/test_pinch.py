"""Every hand can pinch: its thumb pad and index pad can be brought together within their joint ranges.

The search runs on the right hand of each embodiment's robot scene, kinematics only (no contacts, no
servos): the thumb's and the index finger's actuated joints (coupled joints follow their masters as
the equality constraints make them), the other fingers at home.
"""

import mujoco
import numpy as np
import pytest
from embodiment_scenes import fresh_data, robot_scene
from scipy.optimize import minimize
from scipy.stats import qmc

from sim.embodiment.description import load_embodiment

# The pad surfaces may stay at most 1 mm apart (or overlap). That is less than the pads' 2 mm half
# thickness, so the pad faces are what meet, and a servo squeezing past the closing point closes it.
PINCH_GAP_M = 0.001
# The pads must be turned towards each other (normals at least 90 deg apart): a thumb pad lying against
# the back or the far side of the index pad is no pinch. The real kinematics of the linkage hands (the
# Inspire RH56 thumb swings in a plane 2 cm beside the index) do not allow a squarely opposed pinch.
MAX_NORMAL_DOT = 0.0
SAMPLES = 256     # Halton points over the joint box (deterministic), the best few refined by Powell
STARTS = 4


class PinchSearch:
    """Thumb-pad to index-pad gap as a function of the thumb's and the index finger's master joints."""

    def __init__(self, embodiment: str):
        hand = load_embodiment(embodiment).hand
        self.model, layout = robot_scene(embodiment)
        self.data = fresh_data(self.model, layout)
        self.follow = {c.joint: c for c in hand.couplings}
        by_finger = {}
        for link in hand.links:
            by_finger.setdefault(link.finger, []).extend(link.joints)
        self.joints = [j for f in ("thumb", "index") for j in by_finger[f]]
        self.masters = [j for j in self.joints if j.name not in self.follow]
        self.bounds = [j.range for j in self.masters]
        self.adr = {j.name: self.model.joint(f"right_{j.name}").qposadr[0] for j in self.joints}
        self.pads = [self.model.geom(f"right_{s}_tip_pad").id for s in ("thumb", "index")]

    def gap(self, x) -> tuple[float, float]:
        """(signed distance between the pad geoms, dot product of the pad normals) at master angles x."""
        q = {j.name: float(np.clip(v, *j.range)) for j, v in zip(self.masters, x)}
        for j in self.joints:
            if j.name in self.follow:
                c = self.follow[j.name]
                q[j.name] = float(np.clip(np.polyval(c.polycoef[::-1], q[c.master]), *j.range))
        for name, v in q.items():
            self.data.qpos[self.adr[name]] = v
        mujoco.mj_kinematics(self.model, self.data)
        dist = mujoco.mj_geomDistance(self.model, self.data, *self.pads, 0.3, None)
        n = [self.data.geom_xmat[g].reshape(3, 3)[:, 2] for g in self.pads]
        return float(dist), float(n[0] @ n[1])

    def closest(self) -> tuple[float, float, np.ndarray]:
        def cost(x):
            dist, dot = self.gap(x)
            return max(dist, 0.0) + max(0.0, dot - MAX_NORMAL_DOT)   # 1 m per unit of dot: a hard wall
        lo, hi = np.array(self.bounds).T
        xs = lo + qmc.Halton(len(lo), scramble=False).random(SAMPLES + 1)[1:] * (hi - lo)
        starts = np.argsort([cost(x) for x in xs])[:STARTS]
        best = min((minimize(cost, xs[i], method="Powell", bounds=self.bounds,
                             options={"xtol": 1e-4, "ftol": 1e-9, "maxfev": 2000}) for i in starts),
                   key=lambda r: r.fun)
        return (*self.gap(best.x), best.x)


def test_thumb_pad_reaches_the_index_pad(embodiment):
    search = PinchSearch(embodiment)
    dist, dot, x = search.closest()
    where = {j.name: round(float(v), 3) for j, v in zip(search.masters, x)}
    assert dist <= PINCH_GAP_M and dot <= MAX_NORMAL_DOT, (
        f"{load_embodiment(embodiment).hand.path}: closest thumb-index pad approach {dist * 1e3:.1f} mm, "
        f"normals dot {dot:.2f} (want <= {PINCH_GAP_M * 1e3:.0f} mm, <= {MAX_NORMAL_DOT}) at {where}")


def test_the_search_sees_a_thumb_that_cannot_reach():
    """The check can fail: with the thumb held at its open limit the pads stay far apart."""
    search = PinchSearch("ur5_rh56dfx")
    thumb = [i for i, j in enumerate(search.masters) if j.name.startswith("thumb")]
    search.bounds = [(b[0], b[0] + 1e-6) if i in thumb else b for i, b in enumerate(search.bounds)]
    dist, _, _ = search.closest()
    assert dist > 0.01
