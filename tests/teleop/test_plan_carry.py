"""Plan step `carry` (`hand: both`): its load-time check, its keyframes and a real episode carrying
the 1.6 kg cleaner into the wooden box with both hands."""

import dataclasses

import mujoco
import numpy as np
import pytest

from sim import physics
from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.scene.reach import PALM_DOWN
from sim.tasks import load_task
from teleop.recorder import EpisodeRecording
from teleop.scripted_operator import STAGGER_STEPS
from plan_runs import home_and_plan

TASK, EMBODIMENT = "cleaner_box_loading", "xarm7_leap"
STEP = {"hand": "both", "carry": "cleaner", "place": "wooden_box", "place_offset": [-0.07, -0.03, -0.12],
        "grasp_height": 0.08}       # the task's own carry, without its return_home
PALM_NORMAL = PALM_DOWN.T @ np.array([0.0, 0.0, -1.0])      # out of the palm, wrist-site frame
CARRY_END_STEP = 650        # seed 0: lowered into the box, let go and apart (the stage latches at 574)


def _check(steps):
    task = load_task(TASK)
    return parse_plan("t.yaml", {"demo_plan": steps}, PlanScope(task.objects, task.zones, task.points))


@pytest.mark.parametrize("fields, field", [
    ({"hand": "left"}, "hand"),                  # a carry takes both hands
    ({"carry": "bucket"}, "carry"),
    ({"place": "cleaner"}, "place"),             # onto itself
    ({"place_offset": [0.1]}, "place_offset"),
    ({"grasp_height": 0.3}, "grasp_height"),     # above the cleaner's top
    ({"grasp_height": "high"}, "grasp_height"),
    ({"squeeze": 0.01}, "squeeze"),
    ({"toe_in_deg": 45}, "toe_in_deg"),          # past 30 degrees
    ({"toe_in_deg": -5}, "toe_in_deg"),
])
def test_check_refuses_bad_fields(fields, field):
    with pytest.raises(SpecError, match=rf"demo_plan\[0\]\.{field}"):
        _check([{**STEP, **fields}])


def test_only_a_carry_takes_both_hands():
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.hand"):
        _check([{"hand": "both", "pick": "soap", "place": "wooden_box"}])
    assert _check([STEP])[0]["hand"] == "both"


def _operator(plan):
    scene = demonstration_scene(TASK, EMBODIMENT, 0)
    # a copy: the task is load_task's cached one, whose own plan later tests record
    scene.task = dataclasses.replace(scene.task, demo_plan=_check(plan))
    data, op = home_and_plan(scene)
    return scene, data, op


def test_both_hands_start_together_and_squeeze_from_opposite_sides():
    # a one-hand step first: the carry waits for both hands to be free, then keeps them in step
    scene, data, op = _operator([{"hand": "right", "pick": "soap", "place": "table", "place_offset": [0.3, -0.2]},
                                 STEP])
    right, left = ([f.end_step for f in op.sides[s]["timeline"].frames] for s in ("right", "left"))
    # the carry's 11 frames, both hands' way home before them (the pick left the right hand at the table
    # spot) and the hold before that (the return home is the last frame)
    assert right[-14:-1] == left[-14:-1]
    assert left[:2] == [STAGGER_STEPS, right[-14]]        # the left held still until the right's pick ended
    cleaner = op.object_pos(data, "cleaner")
    squeezed = {s: op.sides[s]["timeline"].frames[-10] for s in ("right", "left")}   # approach, descend, squeeze
    normals = {}
    for s, frame in squeezed.items():
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, frame.quat)
        normals[s] = R.reshape(3, 3) @ PALM_NORMAL
        inwards = np.sign(cleaner[0] - frame.pos[0]) * np.array([1.0, 0.0, 0.0])
        assert normals[s] @ inwards > 0.9                                # the palm faces the cleaner
    assert squeezed["right"].pos[0] > cleaner[0] > squeezed["left"].pos[0]
    assert normals["right"] @ normals["left"] < -0.9                     # the palms face each other
    half_across = scene.task.objects["cleaner"].half_extents[0]
    gap = abs(squeezed["right"].pos[0] - squeezed["left"].pos[0])
    assert gap < 2 * half_across                 # aimed inside the faces: the arms press the cleaner in


def test_both_hands_carry_the_cleaner_into_the_box():
    scene, data, op = _operator([STEP])
    episode = EpisodeRecording(scene, data)
    body = scene.object_body_ids["cleaner"]
    z0, lifted = float(data.xpos[body][2]), 0.0
    latched = False
    for step in range(CARRY_END_STEP):
        action = op.act(step, data)
        physics.step_control(scene.model, data, action)
        record = episode.step(data, action)
        lifted = max(lifted, float(data.xpos[body][2]) - z0)
        latched = latched or bool(record.stage_latched[0])
    assert lifted > 0.1               # one LEAP hand never lifted it
    assert latched                    # inside the box and upright (cleaner_in)


def _fingers_in_deg(frame, side: str) -> float:
    """How far a squeezing hand's fingers (the wrist site's z) turn from +y towards the object."""
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, frame.quat)
    fingers = R.reshape(3, 3)[:, 2]
    return float(np.degrees(np.arctan2(-fingers[0] if side == "right" else fingers[0], fingers[1])))


def test_toe_in_turns_the_fingers_in_and_the_wrists_apart():
    turned = {}
    for toe_in in (None, 20.0):
        _, _, op = _operator([STEP if toe_in is None else {**STEP, "toe_in_deg": toe_in}])
        turned[toe_in] = {s: op.sides[s]["timeline"].frames[-10] for s in ("right", "left")}   # squeezed
    for side in ("right", "left"):     # 10 degrees more than TOE_IN_DEG (seen from above: the right's pitched)
        more = _fingers_in_deg(turned[20.0][side], side) - _fingers_in_deg(turned[None][side], side)
        assert 9.0 < more < 13.0
        # the palm itself is where it was: only the hand behind it turns
        assert np.allclose(turned[20.0][side].pos, turned[None][side].pos, atol=0.005)


def test_approach_over_brings_a_hand_over_the_place_and_the_other_waits():
    # ball_box_loading's soccer ball on the UR5+Wuji: straight from home, the right hand's fingers, pointing
    # away from the body, swept the box beside the ball; with approach_over it crosses above the box's top
    soccer = {"hand": "both", "carry": "soccer_ball", "place": "box", "place_offset": [-0.03, 0.03],
              "grasp_height": -0.03}
    scene = demonstration_scene("ball_box_loading", "ur5_wuji", 0)
    task = scene.task
    frames = {}
    for over in (False, True):
        scope = PlanScope(task.objects, task.zones, task.points)
        scene.task = dataclasses.replace(task, demo_plan=parse_plan("t.yaml", {"demo_plan": [
            {**soccer, "approach_over": over}]}, scope))
        data, op = home_and_plan(scene)
        frames[over] = {s: op.sides[s]["timeline"].frames for s in ("right", "left")}
    box_top = op.object_pos(data, "box")[2] + task.objects["box"].half_extents[2]
    # the squeeze (approach, descend, squeeze, ...; the return home last) is where it was, and both hands
    # get there at the same step
    for over in (False, True):
        assert frames[over]["right"][-10].end_step == frames[over]["left"][-10].end_step
    for side in ("right", "left"):
        assert np.allclose(frames[True][side][-10].pos, frames[False][side][-10].pos)
    # straight: the right hand sets off downwards at once; over: it crosses at a height above the box's top
    straight, over = frames[False]["right"], frames[True]["right"]
    assert straight[2].pos[2] < straight[1].pos[2]
    box_left = op.object_pos(data, "box")[0] - task.objects["box"].half_extents[0]
    crossed = over[2].pos           # across at its height to over the ball, past the box's left side
    assert crossed[2] > box_top + 0.05 and crossed[0] < box_left
    assert over[3].pos[2] < crossed[2]          # then down to where the straight approach ends
    assert np.allclose(over[3].pos, straight[2].pos)
