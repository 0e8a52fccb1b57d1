"""`pinch_clear_tips` on a pad pinch: the pre-shape spread until the fingertips, not only the pads, clear
the part (teleop/pinch_tips.py). The LEAP's curled index tip, 3 cm past its pad, came down on the pet
collar's rim and tipped it before the pinch closed (shoebox_accessory_pack, stream path: 7 of 12)."""

import numpy as np
import pytest

from sim import physics
from sim.errors import SpecError
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample, demonstration_seed
from sim.tasks import load_task, parse_task
from teleop.demos import DEFAULT_OPERATOR, OPERATORS
from teleop.flat_pinch import tip_points
from teleop.pinch_grasp import hand_kinematics, pinch_grasp, pinch_preshape, pinch_rows
from teleop.pinch_tips import tips_clear_preshape
from teleop.recorder import home

from task_files import task_file_with_plan

TASK, EMBODIMENT = "shoebox_accessory_pack", "xarm7_leap"
COLLAR = {"hand": "right", "pick": "pet_collar", "place": "shoe_box", "place_offset": [0.105, -0.04, 0.0],
          "grasp": "pinch", "grasp_point": [0.023, 0.045, 0.01], "pinch_clear_tips": True}
WIDTH_M = 0.033     # the collar rim's pinch width: 8 mm across it and the 25 mm margin


def gaps(hand: str, q: np.ndarray) -> tuple[float, float]:
    """(thumb pad to nearest pinching pad, thumb tip to nearest pinching tip) at actuator targets ``q``."""
    kin, fingers = hand_kinematics(hand), pinch_grasp(hand).fingers
    thumb, pads = pinch_rows(hand, fingers)
    P, T = kin.points(q), tip_points(hand, fingers, q)
    return (min(np.linalg.norm(P[thumb] - P[p]) for p in pads),
            min(np.linalg.norm(T[0] - T[k]) for k in range(1, len(T))))


def test_clear_tips_is_a_pad_pinch_field(tmp_path):
    step = {**COLLAR, "grasp": "power"}
    with pytest.raises(SpecError, match=r"collar.yaml: field 'demo_plan\[0\].pinch_clear_tips'.*without grasp: pinch"):
        parse_task(task_file_with_plan(TASK, [step]), tmp_path / "collar.yaml")


@pytest.mark.parametrize("hand", ["leap", "shadow"])
def test_the_tips_clear_the_width_as_the_pads_do(hand):
    """The LEAP's pad pre-shape leaves its index tip 23 mm from the thumb's, 18 mm nearer than the pads;
    spread for the tips, both clear the width. A hand whose tips already clear it (the Shadow's) keeps the pad pre-shape."""
    kin, grasp = hand_kinematics(hand), pinch_grasp(hand)
    pads_only, _ = pinch_preshape(hand, kin.home, grasp.close, WIDTH_M)
    q, centre = tips_clear_preshape(hand, kin.home, grasp.close, WIDTH_M)
    assert min(gaps(hand, q)) >= WIDTH_M
    if hand == "leap":
        assert gaps(hand, pads_only)[1] < WIDTH_M - 0.008
        assert not np.allclose(q, pads_only)
    else:
        assert gaps(hand, pads_only)[1] >= WIDTH_M
        assert np.array_equal(q, pads_only)
        assert np.allclose(centre, pinch_preshape(hand, kin.home, grasp.close, WIDTH_M)[1])


def test_the_collar_stays_upright_as_the_hand_comes_down_and_is_lifted():
    """Stream path, seed 0 (which failed): the hand comes down around the rim without tipping the collar
    (the index tip landed on it before: tipped to 45 degrees), closes, and lifts it."""
    spec = load_task(TASK)
    spec = type(spec)(**{**spec.__dict__, "demo_plan": [dict(COLLAR)]})
    seed = demonstration_seed(TASK, 0)
    scene = build_scene(spec, EMBODIMENT, demonstration_sample(spec, seed))
    data = home(scene)
    op = OPERATORS[DEFAULT_OPERATOR]()
    op.reset(scene, data)
    frames = op.plan.sides["right"]["timeline"].frames
    close = next(i for i in range(1, len(frames)) if not np.allclose(frames[i].hand, frames[i - 1].hand)
                 and frames[i - 1].pos[2] < frames[i - 2].pos[2] - 0.05)     # the closing after the descent
    lifted = next(i for i in range(close, len(frames)) if frames[i].pos[2] > frames[i - 1].pos[2] + 0.05)
    collar = scene.object_body_ids["pet_collar"]
    z0, upright = float(data.xpos[collar][2]), []
    for step in range(frames[lifted].end_step):
        physics.step_control(scene.model, data, op.act(step, data))
        if step < frames[close - 1].end_step:     # down to the closing
            upright.append(float(data.xmat[collar][8]))
    assert min(upright) > 0.99, "the collar tipped as the hand came down"
    assert data.xpos[collar][2] - z0 > 0.05, "the collar was not lifted"
