"""DexPilot retargeting for every catalog hand, from the hand's own description."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import yaml
from scipy.optimize import minimize

from sim.embodiment import hand_names, load_hand
from sim.embodiment.description import DescriptionError
from sim.embodiment.retarget_spec import load_retarget_spec, parse_retarget_spec
from teleop.retarget import DexPilotConfig, DexPilotRetargeter, HandKinematics
from teleop.retarget.bench import run_bench, session_keypoints
from teleop.streams.human_hand import open_hand, pinch

HANDS = hand_names()


def test_catalog_has_twelve_hands_with_a_retarget_block():
    assert len(HANDS) == 12
    for name in HANDS:
        spec = load_retarget_spec(name)
        assert [t.finger for t in spec.fingertips][0] == "thumb"
        assert sorted(t.finger for t in spec.fingertips) == sorted(load_hand(name).fingers)
    assert {len(load_retarget_spec(n).fingertips) for n in HANDS} == {4, 5}


def robot_keypoints(kin: HandKinematics, rt: DexPilotRetargeter, q: np.ndarray) -> np.ndarray:
    """Keypoints of a 'human' whose wrist and fingertips are the robot's own, scaled to human size
    (DexPilot reads only those six keypoints; the others stay at zero)."""
    kp = np.zeros((21, 3))
    kp[rt.keypoint_ids] = kin.points(q) / kin.spec.scale
    return kp


@pytest.mark.parametrize("hand", HANDS)
def test_robot_fingertips_are_retargeted_back(hand):
    rt = DexPilotRetargeter(hand)
    kin = rt.kin
    rng = np.random.default_rng(7)
    for _ in range(6):
        while True:     # a random reachable pose, no pinch (that would project the targets)
            q = rng.uniform(kin.lower, kin.upper)
            tips = kin.points(q)
            if np.linalg.norm(tips[2:] - tips[1], axis=1).min() / kin.spec.scale > DexPilotConfig().escape_dist:
                break
        rt.reset()
        out = rt.retarget(robot_keypoints(kin, rt, q))
        error = np.linalg.norm(kin.points(out) - tips, axis=1).max()
        assert error < 2e-3, f"{hand}: fingertips {error * 1000:.2f} mm from the robot's own pose"


def closest_pinch(kin: HandKinematics) -> float:
    """The smallest thumb-to-index distance this hand can make at all (several bounded starts)."""
    def gap(q):
        p = kin.points(q)
        return float(np.sum((p[1] - p[2]) ** 2))

    rng = np.random.default_rng(0)
    starts = [kin.home, kin.mid] + [rng.uniform(kin.lower, kin.upper) for _ in range(3)]
    best = min(minimize(gap, q0, bounds=list(zip(kin.lower, kin.upper)), method="L-BFGS-B").fun for q0 in starts)
    return float(np.sqrt(best))


@pytest.mark.parametrize("hand", HANDS)
def test_open_hand_opens_and_pinch_closes_thumb_on_index(hand):
    rt = DexPilotRetargeter(hand)
    kin = rt.kin
    home = kin.points(kin.home)
    for _ in range(5):
        q = rt.retarget(open_hand())
    p = kin.points(q)
    reach = np.linalg.norm(p[1:] - p[0], axis=1) / np.linalg.norm(home[1:] - home[0], axis=1)
    assert reach.mean() > 0.9 and reach.min() > 0.8, f"{hand}: open-hand fingertip reach {reach.round(2)}"
    open_gap = np.linalg.norm(p[1] - p[2])

    rt.reset()
    for k in range(30):       # from an open hand into the pinch, then hold it
        s = min(1.0, k / 20)
        q = rt.retarget((1 - s) * open_hand() + s * pinch("index"))
    p = kin.points(q)
    pinch_gap = np.linalg.norm(p[1] - p[2])
    best = closest_pinch(kin)
    assert pinch_gap < best + 3e-3, f"{hand}: pinch {pinch_gap * 1000:.1f} mm, the hand can reach {best * 1000:.1f} mm"
    assert pinch_gap < 0.6 * open_gap


def test_retargeting_is_deterministic():
    keypoints = session_keypoints(30)
    for hand in ("shadow", "rh56dfx", "leap"):
        a, b = DexPilotRetargeter(hand), DexPilotRetargeter(hand)
        first = np.array([a.retarget(kp) for kp in keypoints])
        second = np.array([b.retarget(kp) for kp in keypoints])
        a.reset()
        third = np.array([a.retarget(kp) for kp in keypoints])
        assert first.tobytes() == second.tobytes() == third.tobytes()


@pytest.mark.parametrize("hand", HANDS)
def test_output_respects_joint_limits_on_wild_input(hand):
    rt = DexPilotRetargeter(hand)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = rt.retarget(rng.uniform(-0.3, 0.3, (21, 3)))
        assert q.shape == (len(load_hand(hand).actuators),)
        assert np.all(q >= rt.kin.lower) and np.all(q <= rt.kin.upper)
    with pytest.raises(ValueError, match="finite"):
        rt.retarget(np.full((21, 3), np.nan))
    with pytest.raises(ValueError, match=r"\(21, 3\)"):
        rt.retarget(np.zeros((20, 3)))


@pytest.mark.parametrize("hand", HANDS)
def test_jacobian_over_actuated_joints_matches_finite_differences(hand):
    """The optimiser moves actuated joints only; coupled joints follow through the chain rule."""
    kin = HandKinematics(hand)
    q = np.random.default_rng(1).uniform(kin.lower + 0.05, kin.upper - 0.05)
    _, J = kin.points_and_jacobians(q)
    eps = 1e-6
    numeric = np.stack([(kin.points(q + eps * e) - kin.points(q - eps * e)) / (2 * eps) for e in np.eye(kin.dof)], -1)
    assert np.allclose(J, numeric, atol=1e-6)
    hand_desc = load_hand(hand)
    kin.points(q)
    for c in hand_desc.couplings:       # followers sit where the coupling polynomial puts them
        master = q[[a.joint for a in hand_desc.actuators].index(c.master)]
        expected = np.clip(sum(k * master ** i for i, k in enumerate(c.polycoef)), *hand_desc.joint(c.joint).range)
        assert kin.data.qpos[kin.model.joint(c.joint).qposadr[0]] == pytest.approx(expected)


def test_a_coupling_polynomial_of_any_degree_and_its_slope():
    """The catalog's couplings are linear, but a hand file may give up to five coefficients: the one
    polynomial (builder's home pose, retargeting) and its slope, for several followers at once."""
    from sim.embodiment.description import coupled_position, coupled_slope

    coef = np.array([[0.1, 0.7, -0.3, 0.0, 0.05], [0.7235, 1.0585, 0.0, 0.0, 0.0]])
    x = np.array([0.4, -1.3])
    expected = [sum(c * v ** k for k, c in enumerate(row)) for row, v in zip(coef, x)]
    np.testing.assert_allclose(coupled_position(coef, x), expected, rtol=1e-14)
    assert coupled_position(coef[1], x[1]) == expected[1]          # linear: the same floats
    eps = 1e-6
    numeric = (coupled_position(coef, x + eps) - coupled_position(coef, x - eps)) / (2 * eps)
    np.testing.assert_allclose(coupled_slope(coef, x), numeric, rtol=1e-8)


def test_left_hand_is_the_mirror_of_the_right():
    right, left = DexPilotRetargeter("allegro"), DexPilotRetargeter("allegro")
    for k in range(5):
        kp = (1 - k / 4) * open_hand() + k / 4 * pinch("middle")
        assert np.array_equal(right.retarget(kp, "right"), left.retarget(kp * [-1, 1, 1], "left"))


def test_pinch_projection_switches_with_hysteresis():
    rt = DexPilotRetargeter("shadow")
    rt.retarget(pinch("index"))
    assert rt.projected[0] and not rt.projected[1:].any()
    apart = pinch("index", gap_m=0.04)          # between project (3 cm) and escape (5 cm): still pinching
    rt.retarget(apart)
    assert rt.projected[0]
    rt.retarget(open_hand())
    assert not rt.projected.any()
    rt.reset()
    rt.retarget(apart)
    assert not rt.projected.any()


def raw_block(hand: str) -> dict:
    return copy.deepcopy(yaml.safe_load(load_hand(hand).path.read_text())["retarget"])


@pytest.mark.parametrize("edit, field", [
    (lambda b: b.pop("fingertips"), "retarget.fingertips"),
    (lambda b: b.update(scale=-1), "retarget.scale"),
    (lambda b: b["wrist"].update(body="forearm"), "retarget.wrist.body"),
    (lambda b: b["fingertips"][1].update(keypoint="index_pip"), r"retarget.fingertips\[1\].keypoint"),
    (lambda b: b["fingertips"][2].update(pos=[0, 0]), r"retarget.fingertips\[2\].pos"),
    (lambda b: b["fingertips"].pop(), "retarget.fingertips"),
    (lambda b: b["fingertips"][0].update(keypoint="pinky_tip"), "retarget.fingertips"),
])
def test_retarget_block_errors_name_file_and_field(edit, field):
    block = raw_block("shadow")
    edit(block)
    with pytest.raises(DescriptionError, match=rf"shadow.yaml: field '{field}'"):
        parse_retarget_spec(block, load_hand("shadow"))
    with pytest.raises(DescriptionError, match="field 'retarget': missing"):
        parse_retarget_spec(None, load_hand("shadow"))


def test_bench_reports_every_figure():
    figures = run_bench(["rh5dg2"], frames=6, echo=False)["hands"]["rh5dg2"]
    assert figures["dof"] == 6 and figures["ms_per_step"] > 0 and figures["scipy_ms"] > 0
    assert 0 < figures["worst_cost_ratio_vs_scipy"] < 10
