"""Transit (teleop/transit.py): the scripted operator lifts the hand, and what it carries, over a tall
object standing in the way between two steps, and adds nothing to a timeline with nothing in the way."""

import dataclasses

import mujoco
import numpy as np
import pytest
import yaml

from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample
from sim.tasks import load_task, parse_task
from teleop.transit import CLEARANCE_M, hand_outline
from plan_runs import home_and_plan

BASE, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"
TOWER = {"shape": "box", "size": [0.03, 0.03, 0.15], "mass": 0.3, "rgba": [0.3, 0.3, 0.8, 1.0]}
ORANGE_XY = [0.34, 0.20]       # carried to the plate at [0, 0.16], the tower between
PLAN = [{"hand": "right", "pick": "orange_1", "place": "plate", "place_offset": [0.065, 0.05]},
        {"hand": "right", "pick": "lemon_1", "place": "plate", "place_offset": [0.065, -0.055]}]


def _task(tmp_path, tower_xy):
    raw = yaml.safe_load(load_task(BASE).source.read_text())
    raw["demo_plan"] = PLAN
    raw["objects"]["orange_1"]["pose"]["xy"] = ORANGE_XY
    if tower_xy is not None:
        raw["objects"]["tower"] = {**TOWER, "pose": {"xy": tower_xy}}
    return parse_task(raw, tmp_path / f"transit_{tower_xy is not None}.yaml")


def _operator(tmp_path, tower_xy):
    """The operator planned in a scene with the tower at ``tower_xy`` (None: no tower), every other
    object where it is in the towerless scene's sample."""
    bare = _task(tmp_path, None)
    sample = demonstration_sample(bare, 0)
    task = bare
    if tower_xy is not None:
        task = _task(tmp_path, tower_xy)
        tower = demonstration_sample(task, 0).object_poses["tower"]
        sample = dataclasses.replace(sample, task=task.name, object_poses={**sample.object_poses, "tower": tower})
    scene = build_scene(task, EMBODIMENT, sample)
    data, op = home_and_plan(scene)
    return scene, data, op


def _frames(op):
    frames = op.sides["right"]["timeline"].frames
    return [(f.end_step, f.pos.tolist(), f.quat.tolist(), f.hand.tolist()) for f in frames]


def test_nothing_in_the_way_adds_nothing(tmp_path):
    _, _, bare = _operator(tmp_path, None)
    _, _, far = _operator(tmp_path, [-0.5, 0.32])         # the far left corner, away from both steps
    assert _frames(far) == _frames(bare)
    assert far.length == bare.length


def _lowest_over(op, centre, xy_half, steps):
    """The lowest point of the right hand (open and closed outlines) over the footprint ``centre`` +-
    ``xy_half``, along the timeline's ``steps``."""
    side = op.sides["right"]
    outline = hand_outline(side["hand"], "right", side["open"], side["closed"])
    lowest = np.inf
    for step in steps:
        pos, quat, _ = side["timeline"].at(step)
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, quat)
        pts = pos + outline @ R.reshape(3, 3).T
        over = np.all(np.abs(pts[:, :2] - centre[:2]) < xy_half, axis=1)
        if over.any():
            lowest = min(lowest, pts[over, 2].min())
    return lowest


@pytest.mark.parametrize("tower_xy", [[0.17, 0.17]])
def test_the_hand_and_the_carried_object_rise_over_a_tall_object_in_the_way(tmp_path, tower_xy):
    _, _, bare = _operator(tmp_path, None)
    scene, data, op = _operator(tmp_path, tower_xy)
    body = scene.object_body_ids["tower"]
    top = data.xpos[body][2] + TOWER["size"][2]
    bare_frames, frames = bare.sides["right"]["timeline"].frames, op.sides["right"]["timeline"].frames
    assert len(frames) > len(bare_frames)         # the transits' keyframes
    # the straight moves pass below the tower's top; with transits nothing of the hand that is
    # over the tower comes lower than the clearance above it
    half = np.full(2, TOWER["size"][0])
    steps = range(0, op.sides["right"]["timeline"].end)
    assert _lowest_over(bare, data.xpos[body], half, steps) < top
    assert _lowest_over(op, data.xpos[body], half, steps) >= top + CLEARANCE_M - 1e-6
    # so does the orange while it is held (the hand at its grasp targets), however it sits in the hand
    radius = scene.task.objects["orange_1"].half_extents[2]
    assert _carried_lowest_over(bare, data.xpos[body], half + radius, steps) - radius < top
    carried = _carried_lowest_over(op, data.xpos[body], half + radius, steps)
    assert np.isfinite(carried) and carried - radius >= top + CLEARANCE_M - 1e-6


def _carried_lowest_over(op, centre, xy_half, steps):
    """The lowest the orange's centre comes over the footprint while the right hand holds it."""
    side = op.sides["right"]
    _, name, offset, _ = side["corrections"][0]      # its centre from the wrist, as held (planned)
    assert name == "orange_1"
    closed, lowest = op.power(side, (1.0, 1.0)), np.inf
    for step in steps:
        pos, _, hand = side["timeline"].at(step)
        held = pos + offset
        if np.allclose(hand, closed) and np.all(np.abs(held[:2] - centre[:2]) < xy_half):
            lowest = min(lowest, held[2])
    return lowest


def _model(xml: str):
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    return model, data


def test_a_long_carried_object_is_lifted_over_a_thin_post_between_its_corners():
    """A 24 cm stick carried crosswise over a 1 cm post: its ends pass either side of the post, its
    middle would hit it. Points on the stick's whole surface see the post; its corners alone do not."""
    from teleop.transit import _geom_corners, bounding_box_points, obstacles, transit_height

    model, data = _model("""<mujoco><worldbody>
        <body name="stick" pos="0 -0.3 0.08"><freejoint/><geom type="box" size="0.12 0.01 0.01"/></body>
        <body name="post" pos="0 0 0.05"><geom type="cylinder" size="0.005 0.05"/></body>
        </worldbody></mujoco>""")
    stick, post = model.body("stick").id, model.body("post").id
    in_way = obstacles(model, data, "post", post, np.zeros(3), {})
    above = np.array([[0.0, 0.0, 0.3]])                   # the hand itself passes high over everything
    offset = np.array([0.0, 0.0, -0.1])                   # the stick's centre from the wrist
    start, end, level = np.array([0.0, -0.3, 0.18]), np.array([0.0, 0.3, 0.18]), np.array([1.0, 0, 0, 0])
    corners = _geom_corners(model, data, model.body_geomadr[stick]) - data.xpos[stick] + offset
    assert transit_height(start, level, end, level, above, corners, in_way) is None
    surface = bounding_box_points(model, data, stick) - data.xpos[stick] + offset
    height = transit_height(start, level, end, level, above, surface, in_way)
    stick_bottom = height + offset[2] - 0.01
    assert height is not None and stick_bottom == pytest.approx(0.10 + CLEARANCE_M)


@pytest.mark.parametrize("door_angle, knob_angle", [(np.pi / 2, None), (1.2, 0.7)])
def test_a_link_hanging_from_a_turned_link_turns_with_it(door_angle, knob_angle):
    """A door turned by an earlier step carries its handle round, and a knob on the handle turned too
    comes round with both: each obstacle is where its geom is with the hinges really turned."""
    from teleop.operator_motion import axis_rotation
    from teleop.transit import obstacles

    xml = """<mujoco><worldbody><body name="cabinet" pos="0.3 0 0.2"><geom type="box" size="0.1 0.1 0.2"/>
        <body name="door" pos="0.1 -0.1 0"><joint name="hinge" type="hinge" axis="0 0 1"/>
          <geom type="box" size="0.01 0.1 0.2" pos="0.01 0.1 0"/>
          <body name="handle" pos="0.03 0.17 0"><geom type="box" size="0.01 0.01 0.05"/>
            <body name="knob" pos="0.02 0 0"><joint name="twist" type="hinge" axis="1 0 0"/>
              <geom type="box" size="0.01 0.03 0.005" pos="0.01 0.02 0"/></body>
          </body>
        </body></body></worldbody></mujoco>"""
    model, data = _model(xml)
    turns = {"hinge": door_angle, **({"twist": knob_angle} if knob_angle is not None else {})}
    turned = {}
    for joint, angle in turns.items():
        j = model.joint(joint).id
        turned[int(model.jnt_bodyid[j])] = (data.xanchor[j].copy(), axis_rotation(data.xaxis[j].copy(), angle))
    planned = obstacles(model, data, "cabinet", model.body("cabinet").id, np.zeros(3), turned)
    for joint, angle in turns.items():
        data.qpos[model.jnt_qposadr[model.joint(joint).id]] = angle
    mujoco.mj_kinematics(model, data)
    opened = obstacles(model, data, "cabinet", model.body("cabinet").id, np.zeros(3), {})
    for a, b in zip(planned, opened):
        np.testing.assert_allclose(a.centre, b.centre, atol=1e-12)
        np.testing.assert_allclose(a.rot, b.rot, atol=1e-12)
        assert a.top == pytest.approx(b.top)
