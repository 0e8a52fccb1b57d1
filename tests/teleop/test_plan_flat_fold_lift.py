"""Pick fields `pinch_fold` (a flat pinch's other fingers folded that fraction of the way to their closed end,
default 0.9: folded that far, the DexHand021's pressed a jigsaw piece's top and turned it over in the hand) and
`lift_m` (lifted over the grasp and carried over the place that high, default LIFT_HEIGHT_M: jigsaw's yellow piece,
carried 14 cm up, was set out by the RH56DFX on 2 of 3 seeds). The check takes
pinch_fold on a flat pinch only and both within range; the plan closes with the other fingers folded that far
and carries that high; a plan without them is unchanged."""

import numpy as np
import pytest

from sim.errors import SpecError
from sim.tasks import parse_task
from teleop.flat_pinch import refolded, tip_pinch
from teleop.operator_motion import LIFT_HEIGHT_M
from teleop.pinch_grasp import hand_kinematics

from plan_runs import JIGSAW, JIGSAW_GREEN, plan_steps_on
from task_files import task_file_with_plan

TASK, _ = JIGSAW
EMBODIMENT = "jaka_zu7_dexhand021"


def test_the_check_takes_pinch_fold_on_a_flat_pinch_and_lift_m_in_range(tmp_path):
    step = {**JIGSAW_GREEN, "pinch_fold": 0.5, "lift_m": 0.06}
    plan = parse_task(task_file_with_plan(TASK, [step]), tmp_path / "j.yaml").demo_plan[0]
    assert plan["pinch_fold"] == 0.5 and plan["lift_m"] == 0.06
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.pinch_fold.*without grasp: flat_pinch"):
        parse_task(task_file_with_plan(TASK, [{**step, "grasp": "power", "grasp_yaw": 0}]), tmp_path / "j.yaml")
    for bad in ({"pinch_fold": 1.5}, {"lift_m": 0.5}):
        with pytest.raises(SpecError):
            parse_task(task_file_with_plan(TASK, [{**step, **bad}]), tmp_path / "j.yaml")


def test_refolded_moves_only_the_other_fingers():
    pinch = tip_pinch("dexhand021")
    kin = hand_kinematics("dexhand021")
    half = refolded("dexhand021", pinch.close, 0.5)
    np.testing.assert_array_equal(half[pinch.moving], pinch.close[pinch.moving])
    others = ~pinch.moving
    assert others.any()
    np.testing.assert_allclose(half[others] - kin.home[others], (pinch.close[others] - kin.home[others]) * 0.5 / 0.9)
    np.testing.assert_allclose(refolded("dexhand021", pinch.close, 0.9), pinch.close)


def _frames(step: dict) -> list:
    op, _ = plan_steps_on(TASK, EMBODIMENT, [step])
    return op.sides["right"]["timeline"].frames


def test_the_plan_folds_and_carries_as_asked_and_is_unchanged_without():
    plain, fold, low = _frames(JIGSAW_GREEN), _frames({**JIGSAW_GREEN, "pinch_fold": 0.5}), _frames({**JIGSAW_GREEN, "lift_m": 0.06})
    same = _frames({**JIGSAW_GREEN})
    assert all(np.array_equal(a.pos, b.pos) and np.array_equal(a.hand, b.hand) for a, b in zip(plain, same))
    pinch = tip_pinch("dexhand021")
    folded_plain = max(float(np.abs(np.asarray(f.hand)[~pinch.moving]).sum()) for f in plain)
    folded_half = max(float(np.abs(np.asarray(f.hand)[~pinch.moving]).sum()) for f in fold)
    assert folded_half < folded_plain, "the other fingers fold less"
    assert len(low) == len(plain)
    lower = [float(p.pos[2] - q.pos[2]) for p, q in zip(plain, low)]
    assert max(lower) == pytest.approx(LIFT_HEIGHT_M - 0.06, abs=0.005), "lifted and carried lower by the difference"
    assert min(lower) > -0.005
