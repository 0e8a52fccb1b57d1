"""Plan step `turn`: the check refuses what is not a hinge-jointed link or an angle outside its
range; the keyframes put the fingertips under the bin lid's tab and carry them round the hinge to
the target angle; and a real episode flips the lid open past vertical."""

import mujoco
import numpy as np
import pytest
import yaml

from sim import physics
from sim.errors import SpecError
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample
from sim.tasks import load_task, parse_task
from teleop.demos import DEFAULT_OPERATOR, OPERATORS
from teleop.pinch_grasp import fingertips_in_site_frame
from teleop.plan_steps.turn import FACE_GAP_M, Hinge
from teleop.recorder import home
from plan_runs import home_and_plan

TASK, EMBODIMENT, LID = "trash_disposal", "ur5_rh56dfx", "trash_can/lid"
OPEN_RAD = 1.6
STAYS_OPEN_RAD = 1.45        # near vertical the lid's joint friction holds it; past vertical it falls open


def _raw():
    """The task file with a plan of one step, the right hand opening the lid."""
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    raw["demo_plan"] = [{"hand": "right", "turn": LID, "to": OPEN_RAD}]
    return raw


def _turn_only(tmp_path):
    raw = _raw()
    task = parse_task(raw, tmp_path / "bin.yaml")
    return build_scene(task, EMBODIMENT, demonstration_sample(task, 0))


@pytest.mark.parametrize("turn", ["trash_can/tab", "paper/lid", "trash_can", 3, ["trash_can/lid"]])
def test_turn_refuses_what_is_not_a_hinge_jointed_link(tmp_path, turn):
    raw = _raw()
    raw["demo_plan"][0]["turn"] = turn
    with pytest.raises(SpecError, match=r"bin.yaml: field 'demo_plan\[0\].turn'.*hinge-jointed link from \['trash_can/lid'\]"):
        parse_task(raw, tmp_path / "bin.yaml")


@pytest.mark.parametrize("to", [2.0, -0.1, "open", True, None])
def test_turn_refuses_an_angle_outside_the_joint_range(tmp_path, to):
    raw = _raw()
    raw["demo_plan"][0]["to"] = to
    with pytest.raises(SpecError, match=r"bin.yaml: field 'demo_plan\[0\].to'.*within the joint range \[0, 1.9\]"):
        parse_task(raw, tmp_path / "bin.yaml")


def test_turn_needs_its_fields(tmp_path):
    raw = _raw()
    raw["demo_plan"][0] = {"hand": "right", "turn": LID}
    with pytest.raises(SpecError, match=r"field 'demo_plan\[0\].to'"):
        parse_task(raw, tmp_path / "bin.yaml")


def _pads(op, frame) -> np.ndarray:
    """The index and middle pads (world) at a keyframe of the right hand."""
    side = op.sides["right"]
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, frame.quat)
    tips = fingertips_in_site_frame(side["hand"], side["open"])[1:3].mean(axis=0)
    return frame.pos + R.reshape(3, 3) @ tips


def _planned(scene):
    """The scene at home and a scripted operator that has planned its task's steps there."""
    data, op = home_and_plan(scene)
    return data, op


def test_keyframes_start_under_the_tab_and_end_at_the_target_angle(tmp_path):
    """Set down: the pads are below the tab (the part reaching farthest from the hinge), within its
    footprint, no further below its underside than the set-down gap and a pad's thickness. Last arc
    keyframe: the pads are on the lid turned to the target angle."""
    scene = _turn_only(tmp_path)
    data, op = _planned(scene)
    lid = Hinge(scene.model, data, LID)
    g = lid.handle_geom
    frames = op.sides["right"]["timeline"].frames
    set_down = _pads(op, frames[2])           # start, approach, set down
    local = data.geom_xmat[g].reshape(3, 3).T @ (set_down - data.geom_xpos[g])
    half = scene.model.geom_size[g]
    assert np.all(np.abs(local[:2]) <= half[:2]), f"pads at {local} of the tab, half size {half}"
    assert -half[2] - FACE_GAP_M - 0.02 <= local[2] < -half[2], f"pads {local[2]:.3f} m from the tab's centre"

    # last arc keyframe: the pads are against the lid as it stands at the target angle (within a
    # pad's and the lid's thickness of its mid-plane), between the hinge and the free edge
    last_arc = _pads(op, frames[-5])          # then retreat, rise, home, and the operator's own return home
    handle_at_target = lid.rotated(lid.handle, OPEN_RAD - lid.angle)
    off_plane = (last_arc - lid.anchor) @ lid.tangent(handle_at_target)
    along = (last_arc - lid.anchor) @ lid.radial(handle_at_target)
    assert abs(off_plane) < 0.03, f"pads {off_plane:.3f} m off the lid at {OPEN_RAD} rad"
    assert 0.0 < along < lid.handle_radius, f"pads {along:.3f} m out from the hinge"
    assert op.link_angles[LID] == pytest.approx(1.9)     # let go past vertical, the lid falls open onto its limit


def test_lid_is_flipped_open_through_the_stream_interface(tmp_path):
    """A real episode on the operator the pipeline records with: the lid ends open, resting past
    vertical after the hand has left it, and the can has not moved."""
    scene = _turn_only(tmp_path)
    data = home(scene)
    op = OPERATORS[DEFAULT_OPERATOR]()
    op.reset(scene, data)
    qadr = scene.model.jnt_qposadr[scene.model.joint(LID).id]
    can = scene.object_body_ids["trash_can"]
    start = data.xpos[can].copy()
    step = 0
    while not op.done(step):
        physics.step_control(scene.model, data, op.act(step, data))
        step += 1
    assert data.qpos[qadr] >= STAYS_OPEN_RAD, f"lid at {data.qpos[qadr]:.2f} rad"
    assert np.linalg.norm(data.xpos[can] - start) < 0.01, "the can was pushed"


SCREEN_TASK, SCREEN_EMBODIMENT, SCREEN = "gaming_desk_setup", "jaka_zu7_dexhand021", "monitor/screen"
SCREEN_HALF_WIDTH_M = 0.3       # the panel's half width: it swivels about its middle
STRAIGHT_RAD = 0.14             # the task's monitor_straight stage: |angle| within this


def _screen_scene(tmp_path):
    """The gaming desk with a plan of one step: the left hand swivels the screen to face forward."""
    raw = yaml.safe_load(load_task(SCREEN_TASK).source.read_text())
    raw["demo_plan"] = [{"hand": "left", "turn": SCREEN, "to": 0.0}]
    task = parse_task(raw, tmp_path / "desk.yaml")
    return build_scene(task, SCREEN_EMBODIMENT, demonstration_sample(task, 0))


def test_a_link_spanning_its_hinge_is_pushed_at_the_free_edge_facing_the_hand(tmp_path):
    """The screen's panel is centred on its vertical hinge: the handle is the middle of a free
    edge (a panel's half width out), the one whose pushed face looks towards the hand; a lid's tab,
    out on one side, keeps its centre."""
    scene = _screen_scene(tmp_path)
    data, op = _planned(scene)
    screen = Hinge(scene.model, data, SCREEN)
    hand = op.sides["left"]["home"][0]
    way = -1.0                                  # from 0.44 rad to 0
    screen.choose_edge(way, hand)
    assert screen.handle_radius == pytest.approx(SCREEN_HALF_WIDTH_M, abs=0.01)
    assert (-way * screen.tangent(screen.handle)) @ (hand - screen.handle) > 0, "the pushed face looks away from the hand"

    lid_scene = _turn_only(tmp_path)
    lid_data = home(lid_scene)
    lid = Hinge(lid_scene.model, lid_data, LID)
    tab = lid.handle.copy()
    lid.choose_edge(1.0, lid_scene.model.body("trash_can").pos)
    assert np.array_equal(lid.handle, tab)


def test_screen_is_swivelled_straight_through_the_stream_interface(tmp_path):
    """A real episode on the operator the pipeline records with: the screen ends facing forward
    after the hand has left it."""
    scene = _screen_scene(tmp_path)
    data = home(scene)
    op = OPERATORS[DEFAULT_OPERATOR]()
    op.reset(scene, data)
    qadr = scene.model.jnt_qposadr[scene.model.joint(SCREEN).id]
    step = 0
    while not op.done(step):
        physics.step_control(scene.model, data, op.act(step, data))
        step += 1
    assert abs(data.qpos[qadr]) <= STRAIGHT_RAD, f"screen at {data.qpos[qadr]:.2f} rad"


DOOR_TASK, DOOR_EMBODIMENT, DOOR = "microwave_bowl_loading", "ur5_schunk", "microwave/door"
DOOR_OPEN_RAD = 1.5
DOOR_OPENED_RAD = 1.2           # the task's door_open stage: past this
DOOR_CLOSED_RAD = 0.05          # ... and its door_closed stage: below this
OPEN_HELD_STEPS = 200           # the door stays open while the hand goes home and comes back (longer than that)
# a pull handle: a bar along the door's top front standing off it on two posts, a finger's gap behind it;
# its outer corners reach past the door's free edge, so it is the handle (the part reaching farthest out)
HANDLE_BAR = [{"shape": "box", "size": [0.08, 0.008, 0.008], "pos": [0.42, -0.07, 0.1]},
              {"shape": "box", "size": [0.006, 0.025, 0.008], "pos": [0.36, -0.045, 0.1]},
              {"shape": "box", "size": [0.006, 0.025, 0.008], "pos": [0.48, -0.045, 0.1]}]


def _door_scene(tmp_path, seed=0, close=False):
    """The microwave, its door (opening outwards, towards the robot) given a bar handle, and a plan:
    the right hand pulls the door open (and, with ``close``, then pushes it shut by the bar's front)."""
    raw = yaml.safe_load(load_task(DOOR_TASK).source.read_text())
    # the microwave before the right arm, the bowl and baguette out of the door's swing: the task's own
    # layout puts the microwave before the left hand, which pulls the door in its plan
    for name, pose in {"microwave": {"xy": [0.15, 0.21]}, "bowl": {"xy": [-0.38, 0.05]},
                       "baguette": {"xy": [-0.18, -0.12], "yaw_deg": 20}}.items():
        raw["objects"][name]["pose"] = pose
    door = raw["objects"]["microwave"]["links"]["door"]
    door["parts"] = door["parts"][:1] + HANDLE_BAR      # the door's panel, then this test's bar
    raw["demo_plan"] = [{"hand": "right", "turn": DOOR, "to": DOOR_OPEN_RAD}]
    if close:
        raw["demo_plan"].append({"hand": "right", "turn": DOOR, "to": 0.0})
    task = parse_task(raw, tmp_path / "microwave.yaml")
    return build_scene(task, DOOR_EMBODIMENT, demonstration_sample(task, seed))


def test_a_door_swinging_towards_the_hand_is_pulled_by_its_handle(tmp_path):
    """Set down: the fingers point down and the pads sit in the gap between the bar and the door,
    facing the bar. Last arc keyframe: the pads are behind the bar as it stands at the target angle."""
    scene = _door_scene(tmp_path)
    data, op = _planned(scene)
    door = Hinge(scene.model, data, DOOR)
    bar = door.handle_geom
    assert scene.model.geom_size[bar][0] == pytest.approx(HANDLE_BAR[0]["size"][0]), "the bar is the handle"
    frames = op.sides["right"]["timeline"].frames
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, frames[2].quat)
    assert R.reshape(3, 3)[:, 2] @ np.array([0.0, 0.0, -1.0]) > 0.99, "the fingers point down"
    # in the door's frame (y out of its front face): behind the bar, in front of the door, within the bar's length
    local = data.xmat[door.body].reshape(3, 3).T @ (_pads(op, frames[2]) - data.xpos[door.body])
    bar_x, bar_y = HANDLE_BAR[0]["pos"][:2]
    half = HANDLE_BAR[0]["size"]
    assert abs(local[0] - bar_x) < half[0], f"pads {local[0]:.3f} m along the door, the bar at {bar_x}"
    assert bar_y + half[1] < local[1] < -0.02, f"pads {local[1]:.3f} m off the door, the bar's back at {bar_y + half[1]}"

    last_arc = _pads(op, frames[-5])
    bar_at_target = door.rotated(data.geom_xpos[bar], DOOR_OPEN_RAD - door.angle)
    ahead = (last_arc - bar_at_target) @ door.tangent(bar_at_target)   # the bar moves along the tangent as it opens
    assert -0.02 < ahead < 0.0, f"pads {ahead:.3f} m ahead of the bar at {DOOR_OPEN_RAD} rad, not behind it"


def test_door_is_pulled_open_and_shut_through_the_stream_interface(tmp_path):
    """A real episode on the operator the pipeline records with: the door opens past the task's
    threshold and stays there after the hand has let go of it; the hand, now in front of the door
    (on the side it swings shut towards), comes down in front of the bar and pushes it shut."""
    scene = _door_scene(tmp_path, seed=1, close=True)
    data = home(scene)
    op = OPERATORS[DEFAULT_OPERATOR]()
    op.reset(scene, data)
    qadr = scene.model.jnt_qposadr[scene.model.joint(DOOR).id]
    step, angles = 0, []
    while not op.done(step):
        physics.step_control(scene.model, data, op.act(step, data))
        angles.append(float(data.qpos[qadr]))
        step += 1
    held = sum(a >= DOOR_OPENED_RAD for a in angles)
    assert held >= OPEN_HELD_STEPS, f"the door was past {DOOR_OPENED_RAD} rad for {held} steps, at most {max(angles):.2f} rad"
    assert data.qpos[qadr] <= DOOR_CLOSED_RAD, f"door left at {data.qpos[qadr]:.2f} rad"
