"""The pinch grasp found from each hand's kinematics, and the scripted operator's pinch and drag steps."""

import copy

import numpy as np
import pytest
import yaml

from sim.embodiment.description import DescriptionError
from sim.errors import SpecError
from sim.registry import names
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task, parse_task
from teleop.pinch_grasp import fingertip_rows, hand_kinematics, pinch_grasp, pinch_preshape, pinch_rows
from teleop.recorder import record_episode
from teleop.scripted_operator import ScriptedOperator


def _closest_sampled_gap(hand: str, fingers, samples: int = 4000) -> float:
    """The closest thumb-to-finger pad distance over random actuator targets (seeded)."""
    kin = hand_kinematics(hand)
    thumb, tips = pinch_rows(hand, fingers)
    rng = np.random.default_rng(12345)      # not the solver's own seed: these are other samples
    best = np.inf
    for q in rng.uniform(kin.lower, kin.upper, size=(samples, kin.dof)):
        P = kin.points(q)
        best = min(best, max(np.linalg.norm(P[thumb] - P[t]) for t in tips))
    return best


@pytest.mark.parametrize("hand", names("hands"))
def test_solved_pinch_is_at_least_as_close_as_random_search(hand):
    grasp = pinch_grasp(hand)
    assert grasp.close.shape == (hand_kinematics(hand).dof,)
    assert grasp.gap_m <= _closest_sampled_gap(hand, grasp.fingers) + 1e-3


@pytest.mark.parametrize("hand", names("hands"))
def test_every_hand_brings_the_pads_together(hand):
    assert pinch_grasp(hand).gap_m <= 0.005


def test_preshape_spreads_the_pads_and_centres_the_object_between_them():
    hand = "wuji"
    kin, grasp = hand_kinematics(hand), pinch_grasp(hand)
    q, centre = pinch_preshape(hand, kin.home, grasp.close, 0.06)
    thumb, tips = pinch_rows(hand, grasp.fingers)
    P = kin.points(q)
    assert min(np.linalg.norm(P[thumb] - P[t]) for t in tips) >= 0.06
    # nearer the pinch than a wider pre-shape
    q_wide, _ = pinch_preshape(hand, kin.home, grasp.close, 0.09)
    assert np.linalg.norm(q - grasp.close) < np.linalg.norm(q_wide - grasp.close)
    assert np.all(np.isfinite(centre))


def test_golf_ball_is_pinched_and_lifted():
    """ball_box_loading on UR5+Wuji: the right hand's first pick is a pinch of the golf ball."""
    scene = demonstration_scene("ball_box_loading", "ur5_wuji", 0)
    rec = record_episode(scene, ScriptedOperator(), "pinch", 0, max_steps=300)
    golf = rec.object_names.index("golf_ball")
    z = rec.object_pose[:, golf, 2]
    assert z.max() - z[0] > 0.08, f"golf ball only rose {1000 * (z.max() - z[0]):.0f} mm"


@pytest.mark.parametrize("field, bad", [("grasp", "claw"), ("approach_pitch_deg", 95), ("approach_pitch_deg", "steep"),
                                        ("approach_pitch_deg", True), ("grsp", "pinch"), ("to_zone", "center")])
def test_bad_plan_fields_fail_when_the_task_loads_naming_file_and_field(tmp_path, field, bad):
    """Misspelt or inapplicable fields too: a plan is checked when its task loads, not per episode."""
    raw = yaml.safe_load(load_task("ball_box_loading").source.read_text())
    raw["demo_plan"][1][field] = bad
    with pytest.raises(SpecError, match=rf"balls.yaml: field 'demo_plan\[1\].{field}'"):
        parse_task(raw, tmp_path / "balls.yaml")


def test_drag_pulls_the_bowl_into_the_centre_zone():
    """fruit_bowl_loading on UR5+RH56DFX: the plan's first step hooks the fingers inside the bowl's
    near wall and drags it into the centre zone (|x|, |y| <= 0.1 m) without tipping it."""
    scene = demonstration_scene("fruit_bowl_loading", "ur5_rh56dfx", 0)
    rec = record_episode(scene, ScriptedOperator(), "drag", 0, max_steps=340)
    bowl = rec.object_names.index("bowl")
    start, end = rec.object_pose[0, bowl], rec.object_pose[-1, bowl]
    assert np.linalg.norm(start[:2]) > 0.3 and np.all(np.abs(end[:2]) <= 0.1), f"bowl went {start[:2]} -> {end[:2]}"
    assert abs(end[2] - start[2]) < 0.01, "bowl not resting upright on the table after the drag"


@pytest.mark.parametrize("step, field, expected", [({"hand": "right", "drag": "apple_1", "to_zone": "center"}, "drag", "a container"),
                                                   ({"hand": "right", "drag": "bowl", "to_zone": "shelf"}, "to_zone", "a zone"),
                                                   ({"hand": "right", "drag": "bowl"}, "to_zone", "a value")])
def test_bad_drag_steps_name_file_and_field(tmp_path, step, field, expected):
    raw = yaml.safe_load(load_task("fruit_bowl_loading").source.read_text())
    raw["demo_plan"][0] = step
    with pytest.raises(SpecError, match=rf"bowl.yaml: field 'demo_plan\[0\].{field}'.*{expected}"):
        parse_task(raw, tmp_path / "bowl.yaml")


def test_a_step_after_another_waits_for_it(tmp_path):
    """`after: [0]` on the left hand's first pick holds the left hand until the right hand's drag ends."""
    from sim.scene.builder import build_scene
    from sim.scene.sample import demonstration_sample

    raw = yaml.safe_load(load_task("fruit_bowl_loading").source.read_text())
    plain = parse_task(copy.deepcopy(raw), tmp_path / "bowl.yaml")
    raw["demo_plan"][1]["after"] = [0]
    waiting = parse_task(raw, tmp_path / "bowl.yaml")
    starts = {}
    for name, task in (("plain", plain), ("waiting", waiting)):
        scene = build_scene(task, "ur5_rh56dfx", demonstration_sample(task, 0))
        op = ScriptedOperator()
        op.reset(scene, scene.home_data())
        right, left = op.sides["right"]["timeline"], op.sides["left"]["timeline"]
        drag_end = right.frames[6].end_step          # start, then approach, descend, hook, pull, release, retreat
        sets_off = [a.end_step for a, f in zip(left.frames, left.frames[1:]) if not np.allclose(a.pos, f.pos)]
        starts[name] = (drag_end, sets_off[0])
    assert starts["plain"][1] < starts["plain"][0]          # without it the left hand sets off during the drag
    assert starts["waiting"][1] == starts["waiting"][0]


@pytest.mark.parametrize("after", [[1], [-1], "0", [True]])
def test_after_must_name_earlier_steps(tmp_path, after):
    raw = yaml.safe_load(load_task("fruit_bowl_loading").source.read_text())
    raw["demo_plan"][1]["after"] = after
    with pytest.raises(SpecError, match=r"bowl.yaml: field 'demo_plan\[1\].after'"):
        parse_task(raw, tmp_path / "bowl.yaml")


def test_place_table_sets_the_object_down_at_a_spot_of_the_table(tmp_path):
    """breadbasket_fast_food_loading's second step: the left hand sets the hamburger down at
    (-0.25, -0.18), out of the basket's way, and it stays there on the table."""
    from sim.scene.builder import build_scene
    from sim.scene.sample import demonstration_sample

    task = load_task("breadbasket_fast_food_loading")
    step = task.demo_plan[1]
    assert step["place"] == "table" and step["pick"] == "hamburger"
    scene = build_scene(task, "ur5_rh5dg2", demonstration_sample(task, 0))
    rec = record_episode(scene, ScriptedOperator(), "table", 0, max_steps=700)
    burger = rec.object_names.index("hamburger")
    end = rec.object_pose[-1, burger]
    assert np.linalg.norm(end[:2] - np.array(step["place_offset"])) < 0.03, f"hamburger at {end[:2]}"
    assert abs(end[2] - rec.object_pose[0, burger, 2]) < 0.01      # resting on the table again


def test_a_misspelt_place_lists_the_objects_and_the_table(tmp_path):
    raw = yaml.safe_load(load_task("breadbasket_fast_food_loading").source.read_text())
    raw["demo_plan"][1]["place"] = "tabel"
    with pytest.raises(SpecError, match=r"demo_plan\[1\].place'.*or 'table'"):
        parse_task(raw, tmp_path / "bread.yaml")


@pytest.mark.parametrize("field, bad", [("grasp_yaw", "sideways"), ("grasp_yaw", 200), ("grasp_yaw", True),
                                        ("grasp_point", [0.1, 0.0]), ("grasp_point", "handle")])
def test_bad_grasp_pose_fields_name_file_and_field(tmp_path, field, bad):
    raw = yaml.safe_load(load_task("ball_box_loading").source.read_text())
    raw["demo_plan"][0][field] = bad
    raw["demo_plan"][0].pop("grasp", None)
    with pytest.raises(SpecError, match=rf"balls.yaml: field 'demo_plan\[0\].{field}'"):
        parse_task(raw, tmp_path / "balls.yaml")


def test_a_picks_pinch_may_name_the_part_it_closes_on(tmp_path):
    """A pick's pinch at a grasp_point closes on the part there (teleop/plan_steps/part_pinch.py), a
    flat_pinch's tips either side of it (tests/teleop/test_plan_flat_pinch.py; pour and strike:
    tests/teleop/test_plan_pour.py, test_plan_strike.py)."""
    raw = yaml.safe_load(load_task("ball_box_loading").source.read_text())
    for grasp in ("pinch", "flat_pinch"):
        raw["demo_plan"][0].update(grasp=grasp, grasp_point=[0.0, 0.0, 0.01])
        assert parse_task(raw, tmp_path / "balls.yaml").demo_plan[0]["grasp_point"] == [0.0, 0.0, 0.01]


@pytest.mark.parametrize("pinch", [False, True])
@pytest.mark.parametrize("yaw_deg", [0.0, 35.0, 70.0, 110.0, 160.0])
def test_grasp_yaw_across_closes_the_hand_across_the_narrow_side(pinch, yaw_deg):
    """A bar 0.2 m long and 2.4 cm wide lying at any yaw: the turned hand's closing direction (the
    pinch axis, or the fingers for a power grasp) runs across the bar, and the turn is the smaller one."""
    from sim.embodiment.mirror import mirror_vec
    from teleop.operator_motion import FORWARD, pitched_palm_down, yawed
    from teleop.pinch_grasp import pinch_axis_in_site_frame
    from teleop.plan_steps.pick_place import PALM_DOWN, grasp_yaw, level_pinch_pitch

    a = np.radians(yaw_deg)
    body_rot = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    long_axis = body_rot[:, 0]
    for side in ("right", "left"):
        hand = "orca"
        hand_rot = pitched_palm_down(level_pinch_pitch(hand) if pinch else 0.0)
        turn = grasp_yaw({"hand": side, "grasp_yaw": "across"}, hand_rot, hand, body_rot, (0.1, 0.012, 0.005), pinch)
        assert -np.pi / 2 <= turn < np.pi / 2
        turned = yawed(hand_rot, turn)
        axis = pinch_axis_in_site_frame(hand)
        closing = turned @ ((mirror_vec(axis) if side == "left" else axis) if pinch else PALM_DOWN.T @ FORWARD)
        horizontal = closing[:2] / np.linalg.norm(closing[:2])
        assert abs(horizontal @ long_axis[:2]) < np.sin(np.radians(1.0)), (side, np.degrees(turn))
    assert grasp_yaw({"hand": "right", "grasp_yaw": 30}, hand_rot, hand, body_rot, (0.1, 0.01, 0.01), pinch) == \
        pytest.approx(np.radians(30))


def test_grasp_point_moves_the_grasp_to_that_part_of_the_object(tmp_path):
    """frypan_stand_pour: a power grasp at the pan's handle puts the wrist over the handle, the pan's
    frame offset (rotated into the world) from where it goes for the pan's centre; the carried pan is
    then let go with its centre where it would have gone."""
    from sim.scene.builder import build_scene
    from sim.scene.sample import demonstration_sample

    raw = yaml.safe_load(load_task("frypan_stand_pour").source.read_text())
    handle = [0.15, 0.0, 0.01]
    wrist = {}
    for name, extra in (("centre", {}), ("handle", {"grasp_point": handle})):
        raw["demo_plan"] = [{"hand": "right", "pick": "frypan", "place": "stand", **extra}]
        task = parse_task(copy.deepcopy(raw), tmp_path / "pan.yaml")
        scene = build_scene(task, "ur5_schunk", demonstration_sample(task, 0))
        data = scene.home_data()
        op = ScriptedOperator()
        op.reset(scene, data)
        frames = op.sides["right"]["timeline"].frames
        wrist[name] = (frames[2].pos, frames[-3].pos)       # descended to grasp; lowered to release
        pan_rot = data.xmat[scene.object_body_ids["frypan"]].reshape(3, 3)
    np.testing.assert_allclose(wrist["handle"][0][:2] - wrist["centre"][0][:2], (pan_rot @ handle)[:2], atol=1e-9)
    np.testing.assert_allclose(wrist["handle"][1][:2] - wrist["centre"][1][:2], (pan_rot @ handle)[:2], atol=1e-9)


def test_a_carried_object_clears_its_targets_top_before_it_moves_across():
    """ball_box_loading: every ball is lifted until its bottom is above the box's top (plus the
    clearance) before it is carried over, instead of sweeping across at a fixed lift into the rim."""
    from teleop.plan_steps.pick_place import CARRY_CLEARANCE_M

    scene = demonstration_scene("ball_box_loading", "ur5_wuji", 0)
    data = scene.home_data()
    op = ScriptedOperator()
    op.reset(scene, data)
    task = scene.task
    picks = [s for s in task.demo_plan if "pick" in s]
    checked = 0
    for side in op.sides.values():
        for (_, name, offset, lowered), step in zip(side["corrections"], [s for s in picks if op.sides[s["hand"]] is side]):
            lifted = side["timeline"].frames[lowered.start - 2]     # lift, carry, then lower
            bottom = lifted.pos[2] + offset[2] - task.objects[name].half_extents[2]
            target = step["place"]
            top = data.xpos[scene.object_body_ids[target]][2] + task.objects[target].half_extents[2]
            assert bottom >= top + CARRY_CLEARANCE_M - 1e-9, (name, bottom, top)
            checked += 1
    assert checked == len(picks)


@pytest.mark.parametrize("field, bad", [("pick", ["apple_1"]), ("to_zone", {"center": 1})])
def test_a_plan_name_of_the_wrong_kind_is_named_not_a_type_error(tmp_path, field, bad):
    raw = yaml.safe_load(load_task("fruit_bowl_loading").source.read_text())
    step = 0 if field == "to_zone" else 1
    raw["demo_plan"][step][field] = bad
    with pytest.raises(SpecError, match=rf"bowl.yaml: field 'demo_plan\[{step}\].{field}'"):
        parse_task(raw, tmp_path / "bowl.yaml")


@pytest.mark.parametrize("hand", names("hands"))
def test_fingertip_rows_are_found_by_the_keypoint_each_follows(hand):
    followed = [t.keypoint for t in hand_kinematics(hand).spec.fingertips]
    fingers = fingertip_rows(hand)
    assert "thumb_tip" not in [followed[i] for i in fingers] and len(fingers) == len(followed) - 1
    assert [followed[i] for i in fingertip_rows(hand, ("middle_tip", "index_tip"))] == ["middle_tip", "index_tip"]
    with pytest.raises(DescriptionError, match=r"retarget\.fingertips.*\['sixth_tip'\]"):
        fingertip_rows(hand, ("index_tip", "sixth_tip"))
