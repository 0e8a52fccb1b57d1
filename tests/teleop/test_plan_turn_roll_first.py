"""Plan step `turn`, field `roll_first` (opt-in, default false): before the hand sets off for the link it rolls
about its fingers (once risen, if it rises), then swings them round on its way. On faucet_cup_water_fill the
right hand pushes the mug under the spout palm first, thumb up, then pushes the lever thumb down: half a turn
about a level axis. Tracked in one move, the UR5's IK folds wrist_1 half a turn, the wrist onto its forearm."""

import numpy as np
import pytest
import yaml

from sim.demo_plan import PlanScope, parse_plan
from sim.embodiment.frames import quat_to_mat
from sim.errors import SpecError
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample, demonstration_seed
from sim.tasks import load_task, parse_task
from plan_runs import home_and_plan

TASK, EMBODIMENT = "faucet_cup_water_fill", "ur5_rh56dfx"
PUSH = {"hand": "right", "drag": "mug", "to_zone": "under_faucet", "contact": "palm"}
OPEN = {"hand": "right", "turn": "faucet/handle", "to": 1.4, "speed": 0.05, "after": [0]}


def _right(tmp_path, **fields):
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    raw["demo_plan"] = [PUSH, {**OPEN, **fields}]
    task = parse_task(raw, tmp_path / "faucet.yaml")
    scene = build_scene(task, EMBODIMENT, demonstration_sample(task, demonstration_seed(TASK, 0)))
    _, op = home_and_plan(scene)
    return op.sides["right"]


def _wrist_1_travel(side, first: int, last: int) -> float:
    """How far wrist_1 turns while the stream's IK tracks the timeline from keyframe ``first`` to ``last``."""
    tl, kin, q = side["timeline"], side["kin"], side["q_home"].copy()
    for step in range(0, tl.frames[first].end_step, 2):      # onto the arm's branch there, as the path takes it
        q = kin.ik_tracking(*tl.at(step)[:2], q, side["q_home"], max_iters=30).q
    start, travel = q[3], 0.0
    for step in range(tl.frames[first].end_step, tl.frames[last].end_step + 1, 2):
        q = kin.ik_tracking(*tl.at(step)[:2], q, side["q_home"], max_iters=30).q
        travel = max(travel, abs(q[3] - start))
    return travel


@pytest.mark.parametrize("value", ["yes", 2, None])
def test_check_refuses_a_roll_first_that_is_not_a_flag(value):
    task = load_task(TASK)
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.roll_first"):
        parse_plan("t.yaml", {"demo_plan": [{**OPEN, "roll_first": value}]},
                   PlanScope(task.objects, task.zones, task.points))


def test_the_hand_rolls_over_about_its_fingers_before_it_swings_them_round(tmp_path):
    plain, rolled = _right(tmp_path), _right(tmp_path, roll_first=True)
    P, R = plain["timeline"].frames, rolled["timeline"].frames
    i = next(k for k, (p, r) in enumerate(zip(P, R)) if not np.allclose(p.quat, r.quat))
    assert len(R) == len(P) + 2 and R[-1].end_step > P[-1].end_step
    before, half, over = (quat_to_mat(f.quat) for f in R[i - 1:i + 2])
    assert np.allclose(R[i].pos, R[i - 1].pos) and np.allclose(R[i + 1].pos, R[i - 1].pos), "where it is"
    assert np.allclose(half[:, 2], before[:, 2]) and np.allclose(over[:, 2], before[:, 2]), "about its fingers"
    assert over[:, 0] @ before[:, 0] < -0.99, "over: half a turn (the thumb from up to down)"
    assert half[2, 1] > 0.99, "the palm facing up half way"
    target = quat_to_mat(R[i + 2].quat)
    assert np.allclose(target, quat_to_mat(P[i].quat)), "then on to the turn's approach as planned"
    assert np.degrees(np.arccos(np.clip(target[:, 2] @ over[:, 2], -1, 1))) < 90, "a swing of the fingers left"
    # the why: tracked in one move, wrist_1 folds half a turn; rolled first, it hardly moves
    assert _wrist_1_travel(plain, i - 1, i + 2) > 2.5
    assert _wrist_1_travel(rolled, i - 1, i + 4) < 1.0
