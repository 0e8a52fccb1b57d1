"""`place_from: front` on a pick: the check refuses an unknown value and a place that is not a
container; the opening is found by rays against the container's own walls (the microwave's front,
whatever its door does); the planned path carries the object level to outside the opening, slides it
straight in along the opening, lets it go on the cavity floor and draws the hand back out. And a pinch
at a grasp_point closes on the part there (a bowl's rim)."""

import mujoco
import numpy as np
import pytest
import yaml

from sim.errors import SpecError
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample
from sim.tasks import load_task, parse_task
from teleop.operator_motion import UP
from teleop.pinch_grasp import pinch_axis_in_site_frame, pinch_grasp, pinch_preshape
from teleop.plan_steps.front_place import OUTSIDE_M, RELEASE_GAP_M, opening
from teleop.plan_steps.part_pinch import part_width
from teleop.plan_steps.pick_place import PINCH_SPREAD_MARGIN_M
from teleop.transit import bounding_box_points
from plan_runs import home_and_plan

TASK, EMBODIMENT = "microwave_bowl_loading", "ur5_schunk"
STEP = {"hand": "right", "pick": "bowl", "place": "microwave", "place_from": "front", "grasp_point": [0.07, 0.0, 0.03]}


def _raw(**fields):
    """The task file with one plan step: STEP with ``fields`` (None: left out)."""
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    raw["demo_plan"] = [{k: v for k, v in {**STEP, **fields}.items() if v is not None}]
    return raw


def _planned(tmp_path, **fields):
    task = parse_task(_raw(**fields), tmp_path / "microwave.yaml")
    scene = build_scene(task, EMBODIMENT, demonstration_sample(task, 0))
    data, op = home_and_plan(scene)
    return scene, data, op


@pytest.mark.parametrize("value", ["side", "back", 1, True])
def test_place_from_refuses_an_unknown_value(tmp_path, value):
    with pytest.raises(SpecError, match=r"microwave.yaml: field 'demo_plan\[0\].place_from'.*\['above', 'front'\]"):
        parse_task(_raw(place_from=value), tmp_path / "microwave.yaml")


@pytest.mark.parametrize("place", ["table", "baguette"])
def test_place_from_front_needs_a_container(tmp_path, place):
    with pytest.raises(SpecError, match=r"field 'demo_plan\[0\].place'.*place_from: front, a container from "
                                        r"\['bowl', 'microwave'\]"):
        parse_task(_raw(place=place, pick="baguette"), tmp_path / "microwave.yaml")


def test_the_opening_is_where_no_wall_is_whatever_the_door_does(tmp_path):
    """The microwave is open at -y (towards the robot); its door, shut across that side, is a link and
    not a wall. A bowl is open only at the top: no side to slide into."""
    scene, data, _ = _planned(tmp_path)
    model = scene.model
    mw, bowl = scene.object_body_ids["microwave"], scene.object_body_ids["bowl"]
    front = -data.xmat[mw].reshape(3, 3)[:, 1]        # its own -y (the scene turns it a few degrees)
    assert np.allclose(opening(model, data, mw, data.xpos[mw], np.array([0.0, -1.0, 1.0])), front, atol=1e-6)
    with pytest.raises(SpecError, match="a container open at a side"):
        opening(model, data, bowl, data.xpos[bowl], np.zeros(3))


def test_the_object_slides_in_level_and_the_open_hand_draws_back_out(tmp_path):
    """Frames around the release: outside the opening (the object's leading points OUTSIDE_M clear of
    its plane), slid straight in along it at one height, lowered, let go with the object's centre in
    the cavity just above its floor, the open hand risen off it and drawn back out past the opening."""
    dx = 0.05
    scene, data, op = _planned(tmp_path, place_offset=[dx, -0.05])
    side = op.sides["right"]
    frames = side["timeline"].frames
    opened = next(k for k in range(1, len(frames)) if np.array_equal(frames[k].hand, side["open"])
                  and not np.array_equal(frames[k - 1].hand, side["open"]))
    front, slide, place, rise, back = (frames[opened + k].pos for k in (-3, -2, -1, 1, 2))
    # the object's centre from the wrist, as held: where the plan leaves it, less the release keyframe
    offset = next(p for _, n, p, on in op.moves if n == "bowl" and on == "microwave") + RELEASE_GAP_M * UP - place
    mw = scene.object_body_ids["microwave"]
    task = scene.task
    microwave = task.objects["microwave"]
    cavity, half = np.asarray(microwave.interior_offset), np.asarray(microwave.interior_half_extents)
    R = data.xmat[mw].reshape(3, 3)     # the scene turns the microwave a few degrees: its own frame

    def local(p):
        return (np.asarray(p) - data.xpos[mw]) @ R - cavity     # from the cavity's centre, microwave axes

    mouth_y = -half[1]
    # slid straight in along the opening (+y of the microwave), level
    assert slide[2] == pytest.approx(front[2])
    assert local(slide)[0] == pytest.approx(local(front)[0]) and local(slide)[1] > local(front)[1]
    # outside before: the bowl's leading point clear of the opening's plane
    bowl = scene.object_body_ids["bowl"]
    pts = bounding_box_points(scene.model, data, bowl) - data.xpos[bowl] + offset
    assert local(front + pts)[:, 1].max() <= mouth_y - OUTSIDE_M + 1e-6
    # let go in the cavity, just above its floor, at place_offset from the microwave's centre
    centre = place + offset
    assert local(centre)[2] == pytest.approx(-half[2] + task.objects["bowl"].rest_height + RELEASE_GAP_M)
    assert centre[0] == pytest.approx(data.xpos[mw][0] + dx)
    assert np.all(np.abs(local(centre)) <= half)
    assert local(centre)[1] - task.objects["bowl"].half_extents[1] > mouth_y, "the whole bowl past the opening"
    # the open hand rises off the bowl, under the ceiling, then is drawn back out the way it came
    assert rise[:2] == pytest.approx(place[:2]) and rise[2] > place[2]
    assert local(rise)[2] < half[2]
    assert local(back)[:2] == pytest.approx(local(front)[:2]) and back[2] == pytest.approx(rise[2])
    assert np.allclose(frames[opened - 3].quat, frames[opened].quat), "level: the hand does not turn in the opening"


def test_a_pick_without_place_from_plans_as_before(tmp_path):
    """`place_from: above` is the default: the same timeline as no field."""
    _, _, with_field = _planned(tmp_path, place="table", place_from="above", place_offset=[0.2, -0.2])
    _, _, without = _planned(tmp_path, place="table", place_from=None, place_offset=[0.2, -0.2])
    a, b = with_field.sides["right"]["timeline"].frames, without.sides["right"]["timeline"].frames
    assert [f.end_step for f in a] == [f.end_step for f in b]
    assert all(np.array_equal(f.pos, g.pos) for f, g in zip(a, b))


RIM = [0.0, -0.0725, 0.025]      # the bowl's rim nearest the robot (its wall 5 mm thick at radius 0.07-0.075)


def test_a_pinch_at_a_grasp_point_closes_on_the_part_there(tmp_path):
    """`grasp: pinch` with a grasp_point: the pads spread only as wide as the bowl's wall there (rays
    either side of it), and the point midway between them is that rim point, not the bowl's centre."""
    scene, data, op = _planned(tmp_path, place="table", place_from=None, place_offset=[0.2, -0.2], grasp="pinch",
                               grasp_point=RIM, grasp_yaw=30.0)
    bowl = scene.object_body_ids["bowl"]
    R_bowl = data.xmat[bowl].reshape(3, 3)
    rim = data.xpos[bowl] + R_bowl @ np.asarray(RIM)
    radial = R_bowl @ np.array([0.0, -1.0, 0.0])
    assert part_width(scene.model, data, bowl, rim, radial) == pytest.approx(0.005, abs=0.0015)
    assert part_width(scene.model, data, bowl, rim + 0.1 * UP, radial) == 0.0, "nothing above the rim"
    side = op.sides["right"]
    frames = side["timeline"].frames
    pinch_close = np.clip(pinch_grasp(side["hand"]).close, *scene.model.actuator_ctrlrange[side["hand_ids"]].T)
    closes = next(k for k in range(len(frames)) if np.allclose(frames[k].hand, pinch_close))
    grasp = frames[closes - 1]                  # come down, pre-shaped: where the hand closes
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, grasp.quat)
    axis = R.reshape(3, 3) @ pinch_axis_in_site_frame(side["hand"])
    width = part_width(scene.model, data, bowl, rim, axis) + PINCH_SPREAD_MARGIN_M
    ready, centre = pinch_preshape(side["hand"], side["open"], pinch_close, width)
    assert np.allclose(grasp.hand, ready), "pre-shaped for the wall, not for the whole bowl"
    assert np.allclose(grasp.pos + R.reshape(3, 3) @ centre, rim, atol=1e-9)
