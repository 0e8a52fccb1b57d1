"""Plan step `press`: the check refuses what is not a slide-jointed link, the pointing hand found
from the kinematics, the keyframes over the keys, and real presses on the piano."""

import mujoco
import numpy as np
import pytest
import yaml

from sim import physics
from sim.embodiment.description import quat_to_mat
from sim.errors import SpecError
from sim.scene.builder import build_scene, demonstration_scene
from sim.scene.sample import demonstration_sample
from sim.tasks import load_task, parse_task
from teleop.operator_motion import UP, pitched_palm_down
from teleop.pinch_grasp import hand_kinematics
from teleop.plan_steps.press import CLEARANCE_M, HOVER_M, _lowest, key_geometry, pointing
from teleop.recorder import record_episode
from teleop.scripted_operator import ScriptedOperator
from plan_runs import home_and_plan

TASK, EMBODIMENT = "bimanual_piano_melody", "xarm7_ability"
KEY_HALF_WIDTH_M = 0.011        # the piano's key: box half size across the row


def _raw():
    return yaml.safe_load(load_task(TASK).source.read_text())


@pytest.mark.parametrize("press", [["piano/X9"], ["piano"], [], "piano/C4", [3], ["piano/lid"]])
def test_press_refuses_what_is_not_a_slide_jointed_link(tmp_path, press):
    raw = _raw()
    # a hinge link: a lid is articulated but not a key
    raw["objects"]["piano"]["links"] = {"lid": {"pos": [0, 0.1, 0.03], "joint": {"type": "hinge", "axis": [1, 0, 0],
                                                                               "range": [0, 1.5]},
                                            "parts": [{"shape": "box", "size": [0.2, 0.01, 0.005]}], "mass": 0.3}}
    raw["demo_plan"][0]["press"] = press
    with pytest.raises(SpecError, match=r"piano.yaml: field 'demo_plan\[0\].press'.*slide-jointed links from .*'piano/A3'"):
        parse_task(raw, tmp_path / "piano.yaml")


def test_press_needs_its_fields(tmp_path):
    raw = _raw()
    raw["demo_plan"][0] = {"hand": "right", "press": ["piano/C4"], "grasp": "pinch"}
    with pytest.raises(SpecError, match=r"field 'demo_plan\[0\].grasp'"):
        parse_task(raw, tmp_path / "piano.yaml")


def test_pointing_index_is_the_hands_lowest_point():
    """Only the index actuator stays open, and at the chosen pitch the rest of the hand is at least
    CLEARANCE_M above the index tip, which is well out along the fingers."""
    q, tip, pitch = pointing("ability")
    assert 20.0 <= pitch <= 80.0
    assert np.count_nonzero(q == 0.0) == 1          # the Ability's home is open: only index_flex stays there
    assert tip[2] > 0.08                            # along the fingers, beyond the palm
    kin = hand_kinematics("ability")
    kin.points(q)
    down = pitched_palm_down(pitch).T @ -UP
    others = [link for link in kin.hand.links if link.finger != "index"]
    assert tip @ down - _lowest(kin, others, down) @ down >= CLEARANCE_M


def test_keyframes_put_the_index_tip_on_each_key_in_turn():
    """The right hand's wrist keyframes bring the index tip (from the wrist pose) over each key of
    its melody, HOVER_M above its top between presses and past its full travel when pressing."""
    scene = demonstration_scene(TASK, EMBODIMENT, 0)
    data, op = home_and_plan(scene)
    _, index, _ = pointing("ability")
    frames = op.sides["right"]["timeline"].frames
    tips = np.array([f.pos + quat_to_mat(f.quat) @ index for f in frames])
    keys = scene.task.demo_plan[0]["press"]
    for name in dict.fromkeys(keys):
        top, press, travel = key_geometry(scene.model, data, name)
        on_key = np.linalg.norm(tips[:, :2] - top[:2], axis=1) < 1e-6
        heights = tips[on_key, 2] - top[2]
        assert np.any(np.isclose(heights, HOVER_M)), name
        assert np.isclose(heights.min(), -travel - 0.003), name
        assert np.sum(np.isclose(heights, heights.min())) >= 2 * keys.count(name)   # pressed and held, per press


def test_repeated_key_goes_down_twice_and_nothing_else_moves():
    """Direct joint path, first 230 steps: the right index presses C4, lets it come back up, presses
    it again; no other key of the piano passes the evaluator's press threshold."""
    scene = demonstration_scene(TASK, EMBODIMENT, 0)
    data, op = home_and_plan(scene)
    m = scene.model
    keys = [m.joint(j).name for j in range(m.njnt) if m.joint(j).name.startswith("piano/")]
    adr = np.array([m.jnt_qposadr[m.joint(k).id] for k in keys])
    down = np.zeros(len(keys), bool)
    presses = []
    for step in range(230):
        physics.step_control(m, data, op.act(step, data))
        q = data.qpos[adr]
        newly = (q < -0.008) & ~down
        presses += [keys[i] for i in np.flatnonzero(newly)]
        down = (down | newly) & ~(q > -0.004)
    assert presses == ["piano/C4", "piano/C4"]


def test_piano_episode_plays_the_treble_melody():
    """Direct joint path: the right hand's whole melody latches the treble stage."""
    scene = demonstration_scene(TASK, EMBODIMENT, 0)
    rec = record_episode(scene, ScriptedOperator(), "press", 0, max_steps=600)
    treble = rec.stage_ids.index("treble_melody")
    assert rec.stage_latched[-1, treble]


def test_presses_follow_a_key_whose_object_was_moved(tmp_path):
    """A mouse carried elsewhere before its button is pressed: on setting off, every keyframe of
    the press, the rise off the button included, moves with it (nothing swings back to where the
    mouse was when the plan was made)."""
    raw = yaml.safe_load(load_task("gaming_desk_setup").source.read_text())
    raw["demo_plan"] = [{"hand": "right", "press": ["mouse/left_button"]}]
    task = parse_task(raw, tmp_path / "desk.yaml")
    scene = build_scene(task, "jaka_zu7_dexhand021", demonstration_sample(task, 0))
    data, op = home_and_plan(scene)
    frames = op.sides["right"]["timeline"].frames
    planned = [f.pos.copy() for f in frames]
    shift = np.array([-0.05, 0.03, 0.0])
    adr = scene.model.jnt_qposadr[scene.model.body("mouse").jntadr[0]]
    data.qpos[adr:adr + 3] += shift
    mujoco.mj_forward(scene.model, data)
    op.intent(frames[-1].end_step, data)
    moved = [f.pos - p for f, p in zip(frames, planned)]
    approach = 1                                 # the start frame stays; the approach is the first moved
    assert all(np.allclose(d, shift, atol=1e-5) for d in moved[approach:-1])        # then the operator's return home
    rise = frames[-2].pos - frames[-3].pos
    assert np.allclose(rise[:2], 0.0) and rise[2] > 0, "the hand does not rise straight off the button"
