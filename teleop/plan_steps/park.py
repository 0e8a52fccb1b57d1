"""`park_out_m` (any step): where the other arm's planned path meets this hand resting at home, the hand
rests that far outward of home instead (horizontally, away from the other arm's home): while the step waits
for its `after` steps (back home as the wait ends, so the step sets off as it would without it), and after
the step if it is the hand's last. Where the other arm keeps clear, nothing changes. An arm reaching across
the middle (a pen cup between the hands) can meet the other hand resting at home, which the dry run does
not see: on stationery_category_sorting the JAKA's right forearm, standing the marker in the cup, ran into
the left thumb (its IK 1-5 cm into it), and the left forearm, putting the pen in, into the right hand."""

from __future__ import annotations

import mujoco
import numpy as np

from teleop.operator_motion import DURATIONS, SideTimeline
from teleop.plan_steps.own_arm import contact_depth

# deeper than this the other arm's planned pose meets a hand resting at home: the RM65's right forearm
# grazes the resting left hand by 1-6 mm on 4 of 12 stationery seeds and passes; the JAKA's goes 1-5 cm in
MEET_DEPTH_M = 0.007


def park_pos(op, side: dict, out_m: float) -> np.ndarray:
    """``side``'s home wrist position moved ``out_m`` horizontally away from the other hands' homes."""
    home = np.asarray(side["home"][0], float)
    others = [np.asarray(s["home"][0], float) for s in op.sides.values() if s is not side]
    if not others or out_m <= 0.0:
        return home
    away = home - np.mean(others, axis=0)
    away[2] = 0.0
    return home + out_m * away / np.linalg.norm(away)


def meets_resting(op, data: mujoco.MjData, side: dict, first: int, last: int | None = None) -> bool:
    """Whether the other arm, at its planned keyframes ending after control step ``first`` (up to ``last``),
    goes deeper than MEET_DEPTH_M into ``side``'s arm or hand resting at home (``data``: the scene as
    planned from, both arms at home)."""
    model, sides = op.scene.model, op.scene.layout.sides
    mine = {model.body(b).id for b in (*sides[side["name"]].arm_bodies, *sides[side["name"]].hand_bodies)}
    probe = mujoco.MjData(model)
    for other in (s for s in op.sides.values() if s is not side):
        lay = sides[other["name"]]
        theirs = {model.body(b).id for b in (*lay.arm_bodies, *lay.hand_bodies)}
        q = other["q_home"].copy()
        moved = reaimed(op, data, other)
        for i, frame in enumerate(other["timeline"].frames):
            q = other["kin"].ik(frame.pos + moved[i], frame.quat, q).q     # warm-started along the path, as tracked
            if frame.end_step <= first or (last is not None and frame.end_step > last):
                continue
            if contact_depth(op, data, probe, other["name"], q, mine, theirs) > MEET_DEPTH_M:
                return True
    return False


def reaimed(op, data: mujoco.MjData, side: dict) -> np.ndarray:
    """Per keyframe of ``side``, how far (level) its approach to an object moves at episode time to where
    the plan leaves the object by then (as the dry run's re-aim): a pick of an object an earlier step put
    down is planned where it lay at the start."""
    moved = np.zeros((len(side["timeline"].frames), 3))
    for _, name, planned, span in side["reaims"]:
        shift = op.planned_by_arrival(side, data, name, span) - planned
        shift[2] = 0.0
        moved[span] += shift
    return moved


def rest_pos(op, data: mujoco.MjData, side: dict, out_m: float) -> np.ndarray:
    """Where ``side`` rests after its last step: parked if the other arm's later path meets it at home."""
    if out_m > 0.0 and meets_resting(op, data, side, side["timeline"].end):
        return park_pos(op, side, out_m)
    return np.asarray(side["home"][0], float)


def wait_parked(op, data: mujoco.MjData, side: dict, out_m: float, until: int) -> None:
    """Hold ``side`` until control step ``until``: with ``out_m``, resting at home and a wait long enough, at
    its park pose if the other arm's path meets it at home meanwhile, back home by ``until``."""
    tl: SideTimeline = side["timeline"]
    move = DURATIONS["approach"]
    home_pos, home_quat = side["home"]
    if (out_m > 0.0 and until - tl.end >= 2 * move and np.allclose(tl.frames[-1].pos, home_pos, atol=1e-6)
            and meets_resting(op, data, side, tl.end, until)):
        tl.add(move, pos=park_pos(op, side, out_m), quat=home_quat)
        tl.add(until - move - tl.end)
        tl.add(move, pos=home_pos, quat=home_quat)
    if until > tl.end:
        tl.add(until - tl.end)
