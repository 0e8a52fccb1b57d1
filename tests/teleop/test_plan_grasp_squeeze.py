"""`grasp_squeeze_m` on a flat pinch: the closed tips aimed past each other along the pinch's axis, so
the finger servos press a heavy tool's handle harder (teleop/pinch_squeeze.py). screwdriver_box_hammer's
0.6 kg hammer, flat-pinched with the tips only meeting, slid out between them when the arm stopped over
the block (stream path, 0 of 12)."""

import numpy as np
import pytest

from sim import physics
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task, parse_task
from teleop.demos import DEFAULT_OPERATOR, OPERATORS
from teleop.flat_pinch import tip_pinch, tip_points, tip_preshape
from teleop.pinch_grasp import hand_kinematics
from teleop.pinch_squeeze import squeezed
from teleop.plan_steps.strike import STRIKE_FOLLOW_M, STRIKE_RISE_M
from teleop.recorder import home

from task_files import task_file_with_plan

TASK, EMBODIMENT = "screwdriver_box_hammer", "ur5_rh56dfx"
STRIKE = {"hand": "left", "strike": "wood_block", "tool": "hammer", "strike_point": [0.15, 0.0, -0.018],
          "place": "box", "grasp": "flat_pinch", "grasp_point": [0.05, 0.0, 0.0], "grasp_squeeze_m": 0.03}


@pytest.mark.parametrize(("fields", "expected"), [
    ({"grasp": "pinch", "grasp_point": None}, "no grasp_squeeze_m without grasp: flat_pinch"),
    ({"grasp_squeeze_m": 0.2}, "metres in \\[0, 0.05\\]"),
])
def test_the_squeeze_is_a_flat_pinch_field(tmp_path, fields, expected):
    step = {k: v for k, v in {**STRIKE, **fields}.items() if v is not None}
    with pytest.raises(SpecError, match=rf"hammer.yaml: field 'demo_plan\[0\].grasp_squeeze_m'.*{expected}"):
        parse_task(task_file_with_plan(TASK, [step]), tmp_path / "hammer.yaml")


@pytest.mark.parametrize("hand", ["rh56dfx", "revo2"])
def test_the_thumb_tip_is_aimed_past_the_fingers_tips_by_the_depth(hand):
    """Along the pinch axis by the depth (linearised at the closed shape: within 4 mm at 3 cm), moving only the pinch's
    joints, and mostly their flexion: the thumb's swing over the palm moves least."""
    grasp = tip_pinch(hand)
    ready, _ = tip_preshape(hand, hand_kinematics(hand).home, grasp.close, 0.045)
    P = tip_points(hand, grasp.fingers, ready)
    axis = (P[1:].mean(axis=0) - P[0]) / np.linalg.norm(P[1:].mean(axis=0) - P[0])

    def past(q):
        T = tip_points(hand, grasp.fingers, q)
        return float((T[0] - T[1:].mean(axis=0)) @ axis)

    assert np.array_equal(squeezed(hand, grasp.close, ready, 0.0), grasp.close)
    q = squeezed(hand, grasp.close, ready, 0.03)
    assert past(q) - past(grasp.close) == pytest.approx(0.03, abs=0.004)
    moved = np.flatnonzero(np.abs(q - grasp.close) > 1e-9)
    assert len(moved) == 1 + len(grasp.fingers) + 1     # the thumb's two joints and the pinching fingers'
    assert np.argmin(np.abs(q - grasp.close)[moved]) == 0     # the thumb's rotation over the palm least


def test_the_squeezed_hammer_stays_in_the_hand_over_the_block():
    """Stream path, seed 0: carried to the ready pose over the block and held there, the hammer keeps
    its height in the hand (with the tips only meeting it slid 10 cm down onto the block)."""
    spec = load_task(TASK)
    spec = type(spec)(**{**spec.__dict__, "demo_plan": [dict(STRIKE)]})
    scene = demonstration_scene(spec, EMBODIMENT)
    data = home(scene)
    op = OPERATORS[DEFAULT_OPERATOR]()
    op.reset(scene, data)
    frames = op.plan.sides["left"]["timeline"].frames
    lift = next(i for i in range(3, len(frames)) if frames[i].pos[2] > frames[i - 1].pos[2] + 0.1)
    down = STRIKE_RISE_M + STRIKE_FOLLOW_M
    swing = next(i for i in range(lift, len(frames))
                 if np.allclose(frames[i - 1].pos - frames[i].pos, [0.0, 0.0, down], atol=1e-9))
    held = frames[swing - 1].end_step       # lifted, carried to the ready pose and held over the block
    hammer, wrist = scene.object_body_ids["hammer"], op.plan.sides["left"]["wrist_site_id"]
    below = []
    for step in range(held):
        physics.step_control(scene.model, data, op.act(step, data))
        if step >= frames[lift].end_step:
            below.append(float(data.site_xpos[wrist][2] - data.xpos[hammer][2]))
    assert max(below) - min(below) < 0.01, "the hammer slid in the hand"
