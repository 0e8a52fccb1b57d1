"""Pick field `pinch_fingers` with `grasp: flat_pinch`: the fingers whose tips the thumb's tip closes against
(default the hand's pad pinch set, teleop/pinch_grasp.py). The Inspire hands' own set is the index alone: the
folded middle finger's link lay on a jigsaw piece and tilted it 34 degrees in the hand; with [index, middle]
they lift and set down green and red (jigsaw_puzzle_assembly). The check takes the field on a flat pinch; the
plan closes to that set's tips and comes down turned and pre-shaped for it; a hand whose own set it is (the
Sharpa's) and a plan without the field are unchanged."""

import numpy as np
import pytest

from sim.errors import SpecError
from sim.tasks import parse_task
from teleop.flat_pinch import flat_pinch_rotation, tip_axis, tip_pinch, tip_preshape
from teleop.pinch_grasp import hand_kinematics

from plan_runs import JIGSAW, JIGSAW_GREEN, plan_steps_on
from task_files import task_file_with_plan

TASK, _ = JIGSAW
PAIR = ("index", "middle")


def test_the_check_takes_pinch_fingers_on_a_flat_pinch_only(tmp_path):
    step = {**JIGSAW_GREEN, "pinch_fingers": list(PAIR)}
    assert parse_task(task_file_with_plan(TASK, [step]), tmp_path / "j.yaml").demo_plan[0]["pinch_fingers"] == list(PAIR)
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.pinch_fingers.*without grasp: pinch or flat_pinch"):
        parse_task(task_file_with_plan(TASK, [{**step, "grasp": "power", "grasp_yaw": 0}]), tmp_path / "j.yaml")


def test_the_tips_pinch_the_named_set():
    own, pair = tip_pinch("rh56dfx"), tip_pinch("rh56dfx", PAIR)
    assert own.fingers == ("index",) and pair.fingers == PAIR
    assert not np.allclose(own.close, pair.close)
    kin = hand_kinematics("rh56dfx")
    touch, _ = tip_preshape("rh56dfx", kin.home, pair.close, 0.1, PAIR)
    assert not np.allclose(tip_axis("rh56dfx", touch, PAIR), tip_axis("rh56dfx", touch))
    # the Sharpa's own set is index and middle: naming it changes nothing
    np.testing.assert_array_equal(tip_pinch("sharpa", PAIR).close, tip_pinch("sharpa").close)
    ready = tip_preshape("sharpa", hand_kinematics("sharpa").home, tip_pinch("sharpa").close, 0.1)[0]
    np.testing.assert_array_equal(flat_pinch_rotation("sharpa", "right", ready, PAIR),
                                  flat_pinch_rotation("sharpa", "right", ready))


def _timeline(embodiment: str, step: dict) -> list:
    op, _ = plan_steps_on(TASK, embodiment, [step])
    return [(f.end_step, np.asarray(f.pos), np.asarray(f.quat), np.asarray(f.hand)) for f in op.sides["right"]["timeline"].frames]


def _hand_ranges(embodiment: str) -> tuple[np.ndarray, np.ndarray]:
    op, _ = plan_steps_on(TASK, embodiment, [JIGSAW_GREEN])
    return op.scene.model.actuator_ctrlrange[op.sides["right"]["hand_ids"]].T


def _same(a: list, b: list) -> bool:
    return len(a) == len(b) and all(x[0] == y[0] and all(np.array_equal(u, v) for u, v in zip(x[1:], y[1:]))
                                    for x, y in zip(a, b))


def test_the_plan_closes_to_the_named_tips_and_is_unchanged_without_them():
    plain, pair = (_timeline("ur5_rh56dfx", s) for s in (JIGSAW_GREEN, {**JIGSAW_GREEN, "pinch_fingers": list(PAIR)}))
    assert not _same(plain, pair)
    lo, hi = _hand_ranges("ur5_rh56dfx")
    for frames, fingers in ((plain, None), (pair, PAIR)):
        closed = np.clip(tip_pinch("rh56dfx", fingers).close, lo, hi)
        assert any(np.allclose(f[3], closed, atol=1e-9) for f in frames), "each closes to its own set's tips"
    assert _same(_timeline("iiwa7_sharpa", JIGSAW_GREEN), _timeline("iiwa7_sharpa", {**JIGSAW_GREEN, "pinch_fingers": list(PAIR)}))
