"""The arm IK's fallback: a warm start that lost its branch is solved again from home
(`ArmKinematics.ik_again_from`), in the kinematics, the live session's CLIK and the plan's dry run."""

import mujoco
import numpy as np

import sim.physics as physics
from sim.embodiment import ArmKinematics, add_bimanual_robot, load_embodiment
from sim.embodiment.builder import home_arm_angles
from sim.embodiment.description import Transform
from sim.embodiment.kinematics import AGAIN_CLOSER
from teleop.cross_embodiment import plan_reach
from teleop.retarget import TeleopCommander

EMBODIMENT = "xarm7_ability"


def arm(name: str = EMBODIMENT):
    emb = load_embodiment(name)
    kin = ArmKinematics(emb.arm, emb.mounts["right"], emb.hand, "right")
    home = np.array(home_arm_angles(name)[1])
    pos, quat = kin.fk(home)
    return kin, home, pos + np.array([0.0, 0.1, -0.1]), quat     # 14 cm from home: reachable from there


def lost_branch(kin: ArmKinematics) -> np.ndarray:
    """A joint pose (seeded) from which 300 warm-started iterations do not reach the target."""
    return np.random.default_rng(0).uniform(kin.ik_lower, kin.ik_upper)


def test_a_missed_warm_start_is_solved_again_from_home():
    kin, home, pos, quat = arm()
    warm = kin.ik(pos, quat, lost_branch(kin), max_iters=300)
    assert not warm.success and warm.pos_err_m > 0.05
    again = kin.ik_again_from(warm, pos, quat, home, max_iters=30)
    assert again.success and again.miss <= 1.0 < warm.miss
    assert again.from_home and not warm.from_home


def test_ik_tracking_is_the_warm_solve_then_the_solve_from_home():
    kin, home, pos, quat = arm()
    tracked = kin.ik_tracking(pos, quat, lost_branch(kin), home, max_iters=30)
    by_hand = kin.ik_again_from(kin.ik(pos, quat, lost_branch(kin), max_iters=30), pos, quat, home, max_iters=30)
    assert tracked.from_home and np.array_equal(tracked.q, by_hand.q)
    assert not kin.ik_tracking(pos, quat, home, home, max_iters=30).from_home     # the warm start reached it


def test_a_warm_start_that_succeeds_is_kept_as_it_is():
    kin, home, pos, quat = arm()
    warm = kin.ik(pos, quat, home, max_iters=30)
    assert warm.success
    assert kin.ik_again_from(warm, pos, quat, lost_branch(kin), max_iters=30) is warm     # not even solved again


def test_a_miss_from_home_that_is_not_much_closer_is_not_kept():
    """Out of reach from both: the warm start stays (no swing over to another branch for a few mm)."""
    kin, home, pos, quat = arm()
    out_of_reach = pos + np.array([0.0, 3.0, 0.0])
    warm = kin.ik(out_of_reach, quat, home, max_iters=30)
    from_elsewhere = kin.ik(out_of_reach, quat, lost_branch(kin), max_iters=30)
    assert not warm.success and not from_elsewhere.success
    assert from_elsewhere.miss > AGAIN_CLOSER * warm.miss
    assert kin.ik_again_from(warm, out_of_reach, quat, lost_branch(kin), max_iters=30) is warm


def test_the_live_clik_recovers_a_lost_branch_instead_of_holding():
    """Before the fallback the commander flagged such a pose unreachable and held its last target."""
    spec = mujoco.MjSpec()
    physics.configure_options(spec)
    layout = add_bimanual_robot(spec, EMBODIMENT)
    model = spec.compile()
    commander = TeleopCommander(model, layout)
    s = commander.sides["right"]
    kin, _, pos, quat = arm()
    s.arm_q = lost_branch(kin)      # where a long stretch of the operator's path may have left the arm
    ok, why = commander._arm(s, Transform(pos, s.kin.fk_se3(s.home_arm).rotation))
    assert ok, why
    reached, _ = s.kin.fk(s.arm_q)
    assert np.linalg.norm(reached - pos) < 2e-3


def test_dry_run_of_another_arms_plan_stays_on_the_path():
    """citrus_plate_loading's plan on the xArm7: the left arm's warm start misses on a few steps, and
    solved again from home there it stays on the path. (condiment_box_loading's plan, whose warm start
    strayed up to 115 cm at stop 26, takes its bottles from the side since stop 35 and no longer misses.)"""
    reach = plan_reach("citrus_plate_loading", EMBODIMENT)
    assert reach["left"]["from_home_steps"] > 0
    assert reach["left"]["worst_m"] < 0.05 and reach["left"]["off_path_steps"] == 0
