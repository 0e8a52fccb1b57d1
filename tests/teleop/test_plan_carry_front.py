"""Plan step `carry` with `place_from: front`: both palms carry an object in level through the side a
container is open at (a bowl into a microwave). The check refuses a place that is not a container;
the planned path holds both hands in step, carries the object to outside the opening, slides it
straight in, lets it go on the cavity floor, parts the palms until the hands clear it and draws them
back out; the palms hold it across the opening, and the fingers pitch down no lower than the object's
bottom (they caught the microwave's floor)."""

import mujoco
import numpy as np
import pytest
import yaml

from sim.errors import SpecError
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample
from sim.tasks import load_task, parse_task
from teleop.plan_steps.carry import AT_HOME_M, FINGERS_DOWN_DEG, RIM_CLEAR_M, SQUEEZE_M, fingers_pitch
from teleop.plan_steps.front_place import OUTSIDE_M, RELEASE_GAP_M, SLIDE_CLEARANCE_M
from teleop.transit import bounding_box_points, hand_outline
from plan_runs import home_and_plan

TASK, EMBODIMENT = "microwave_bowl_loading", "ur5_schunk"
# grasp_height: the palms this far above its centre, so that level their lower edge clears its bottom
STEP = {"hand": "both", "carry": "bowl", "place": "microwave", "place_from": "front", "place_offset": [0.02, -0.05],
        "grasp_height": 0.015}
# the carry's frames from its end (the operator adds the way home last): out to the opening, in, down,
# open, off the object's side, up off its top, apart, back out
OUTSIDE, SLIDE, LOWER, OPEN, EASE, RISE, APART, BACK = range(-9, -1)
SQUEEZE = -13


def _raw(**fields):
    """The task file with one plan step: STEP with ``fields`` (None: left out)."""
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    raw["demo_plan"] = [{k: v for k, v in {**STEP, **fields}.items() if v is not None}]
    return raw


def _planned(tmp_path, before=()):
    raw = _raw()
    raw["demo_plan"] = [*before, {**raw["demo_plan"][0], "after": list(range(len(before)))}]
    task = parse_task(raw, tmp_path / "microwave.yaml")
    scene = build_scene(task, EMBODIMENT, demonstration_sample(task, 0))
    data, op = home_and_plan(scene)
    return scene, data, op


@pytest.mark.parametrize(("fields", "field", "expected"), [
    ({"place_from": "side"}, "place_from", r"\['above', 'front'\]"),
    ({"place": "table"}, "place", r"with place_from: front, a container from \['microwave'\]"),
    ({"place": "baguette"}, "place", r"with place_from: front, a container from \['microwave'\]"),
    ({"place_from": None, "slide_clearance_m": 0.06}, "slide_clearance_m", r"no slide_clearance_m without place_from"),
    ({"slide_clearance_m": 0.2}, "slide_clearance_m", r"metres in \[0, 0.15\]"),
])
def test_the_check_refuses_a_bad_way_in(tmp_path, fields, field, expected):
    with pytest.raises(SpecError, match=rf"field 'demo_plan\[0\]\.{field}'.*{expected}"):
        parse_task(_raw(**fields), tmp_path / "microwave.yaml")


def _rot(q):
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, q)
    return R.reshape(3, 3)


def test_both_palms_slide_it_in_level_let_go_on_the_floor_and_part_clear_of_it(tmp_path):
    scene, data, op = _planned(tmp_path)
    task = scene.task
    frames = {s: op.sides[s]["timeline"].frames for s in ("right", "left")}
    assert [f.end_step for f in frames["right"][SQUEEZE:]] == [f.end_step for f in frames["left"][SQUEEZE:]]
    mw, bowl = scene.object_body_ids["microwave"], scene.object_body_ids["bowl"]
    R = data.xmat[mw].reshape(3, 3)      # the scene turns the microwave a few degrees: its own frame
    microwave = task.objects["microwave"]
    cavity, half = np.asarray(microwave.interior_offset), np.asarray(microwave.interior_half_extents)

    def local(p):
        return (np.asarray(p) - data.xpos[mw]) @ R - cavity     # from the cavity's centre, microwave axes

    # the palms either side of it across the opening (the microwave's x axis), not the bowl's own
    # axes (the scene turns them differently: 2 and -15 degrees in this sample)
    between = frames["right"][SQUEEZE].pos - frames["left"][SQUEEZE].pos
    assert between @ R[:, 0] / np.linalg.norm(between) > 0.9999
    start = data.xpos[bowl].copy()
    bottom = start[2] - bounding_box_points(scene.model, data, bowl)[:, 2].min()
    bowl_pts = bounding_box_points(scene.model, data, bowl) - start
    for side, fr in frames.items():
        held = fr[SQUEEZE].pos - start                  # the wrist from the bowl's centre, as held
        outline = hand_outline(op.sides[side]["hand"], side, op.sides[side]["open"]) @ _rot(fr[SQUEEZE].quat).T
        assert outline[:, 2].min() >= -(held[2] + bottom) - 1e-9, f"{side}: fingertips below the bowl's bottom"
        # carried level to outside the opening, everything held clear of its plane, then straight in
        outside, slide = fr[OUTSIDE].pos, fr[SLIDE].pos
        assert slide[2] == pytest.approx(outside[2])
        assert local(slide)[0] == pytest.approx(local(outside)[0]) and local(slide)[1] > local(outside)[1]
        assert local(outside - held + bowl_pts)[:, 1].max() <= -half[1] - OUTSIDE_M + 1e-6
        assert local(outside + outline)[:, 1].max() <= -half[1] - OUTSIDE_M + 1e-6
        # let go just above the cavity floor, at place_offset from the microwave's centre
        centre = fr[LOWER].pos - held
        assert local(centre)[2] == pytest.approx(-half[2] + task.objects["bowl"].rest_height + RELEASE_GAP_M)
        assert centre[:2] == pytest.approx(data.xpos[mw][:2] + STEP["place_offset"])
        assert np.array_equal(fr[OPEN].pos, fr[LOWER].pos)
        # off the bowl's side, then what of the open hand is over the bowl (a thumb over its rim) rises
        # clear of its top; the palms part until the whole open hand is clear of its side, then draw
        # straight back out
        out = np.sign(fr[EASE].pos[0] - centre[0]) * R[:, 0]
        assert (fr[EASE].pos - fr[OPEN].pos) @ out == pytest.approx(SQUEEZE_M)
        rise = fr[RISE].pos - fr[EASE].pos
        assert rise[:2] == pytest.approx([0.0, 0.0]) and rise[2] > 0.0
        over = fr[RISE].pos - centre + hand_outline(op.sides[side]["hand"], side, op.sides[side]["open"]) \
            @ _rot(fr[RISE].quat).T
        bowl_half = task.objects["bowl"].half_extents
        over = over[(over @ out < bowl_half[0] - RIM_CLEAR_M) & (np.abs(over @ R[:, 1]) <= bowl_half[1])]
        assert len(over) and over[:, 2].min() >= bowl_pts[:, 2].max() + RIM_CLEAR_M - 1e-6
        assert fr[APART].pos[2] == pytest.approx(fr[RISE].pos[2])
        across = (fr[APART].pos - fr[OPEN].pos) / np.linalg.norm(fr[APART].pos - fr[OPEN].pos)
        hand = fr[APART].pos - centre + hand_outline(op.sides[side]["hand"], side, op.sides[side]["open"]) \
            @ _rot(fr[APART].quat).T
        assert (hand @ across).min() >= task.objects["bowl"].half_extents[0]
        assert np.allclose(fr[BACK].pos - fr[APART].pos, outside - slide), "back out the way it came in"
    assert [(name, on) for _, name, _, on in op.moves] == [("bowl", "microwave")]


def test_slide_clearance_m_raises_the_slide_in_and_nothing_else(tmp_path):
    """slide_clearance_m: the object's bottom that high over the cavity floor as it slides in (default
    SLIDE_CLEARANCE_M): the frames outside the opening and slid in are raised by the difference, the
    rest are where they were (a bowl hung tilted from the RH5DG2's thumbs caught the microwave's front
    edge 4 cm up)."""
    def planned(**fields):
        raw = _raw(**fields)
        task = parse_task(raw, tmp_path / "microwave.yaml")
        scene = build_scene(task, EMBODIMENT, demonstration_sample(task, 0))
        return home_and_plan(scene)[1].sides["right"]["timeline"].frames
    default, raised = planned(), planned(slide_clearance_m=SLIDE_CLEARANCE_M + 0.02)
    assert len(default) == len(raised)
    for k, (a, b) in enumerate(zip(default, raised)):
        lift = 0.02 if k - len(default) in (OUTSIDE, SLIDE) else 0.0
        assert b.pos - a.pos == pytest.approx([0.0, 0.0, lift], abs=1e-9), k
    assert planned(slide_clearance_m=SLIDE_CLEARANCE_M)[SLIDE].pos == pytest.approx(default[SLIDE].pos)


def test_the_fingers_pitch_down_only_as_far_as_the_object_s_bottom(tmp_path):
    """The right hand's fingers pitch FINGERS_DOWN_DEG where they clear what the object stands on (a
    tall cleaner), less for a low one (the bowl), level at the least."""
    _, _, op = _planned(tmp_path)
    across = np.array([1.0, 0.0, 0.0])
    assert fingers_pitch(op, "right", across, 1.0) == FINGERS_DOWN_DEG["right"] == 30.0
    low = fingers_pitch(op, "right", across, 0.07)
    assert 0.0 < low < FINGERS_DOWN_DEG["right"]
    assert fingers_pitch(op, "right", across, 0.0) == 0.0


def test_a_hand_an_earlier_step_left_elsewhere_goes_home_before_the_carry(tmp_path):
    """Both hands set off for the object from home: after the right hand has laid the baguette in the
    bowl (its last keyframe above the bowl), both first go to their home poses together (the left one,
    already there, holds still); hands already at home set off straight away."""
    _, _, op = _planned(tmp_path, before=[{"hand": "right", "pick": "baguette", "place": "bowl", "grasp_yaw": 90}])
    homes = {s: op.sides[s]["timeline"].frames[SQUEEZE - 3] for s in ("right", "left")}
    assert homes["right"].end_step == homes["left"].end_step
    for s, frame in homes.items():
        assert np.allclose(frame.pos, op.sides[s]["home"][0]) and np.allclose(frame.quat, op.sides[s]["home"][1])
    placed = op.sides["right"]["timeline"].frames[SQUEEZE - 4]
    assert np.linalg.norm(placed.pos - op.sides["right"]["home"][0]) > AT_HOME_M, "the pick left the hand elsewhere"
    _, _, straight = _planned(tmp_path)
    # start, the hold until the left hand starts (STAGGER_STEPS), approach, descend, squeeze .. back, home
    assert len(straight.sides["right"]["timeline"].frames) == 2 + 2 - SQUEEZE
