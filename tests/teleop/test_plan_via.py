"""`pick` with `via` stops and `hold: true` (teleop/plan_steps/via.py): the plan check, where the planned
wrist takes the carried object's via point (into a pot's cavity below its rim, over a bowl clear of its
top, `via_times` rounds), and a real hold: a bowl kept lifted in the left hand at the end of its step."""

import dataclasses

import numpy as np
import pytest

from sim import physics
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task, parse_task
from teleop.plan_steps.via import VIA_DURATIONS, VIA_INSIDE_DEPTH_M, VIA_OVER_CLEARANCE_M

from task_files import task_file_with_plan
from plan_runs import home_and_plan

TASK, EMBODIMENT = "soup_serving", "ur5_shadow"
# the task's own plan: the left hand holds the bowl up beside the pot, the right ladles twice
HOLD = dict(load_task(TASK).demo_plan[0])
SCOOP = {k: v for k, v in load_task(TASK).demo_plan[1].items() if k != "after"}
LADLE_BOWL = SCOOP["via_point"]         # the ladle's bowl in its frame (the task's two_scoops stage tests it)


def _parse(tmp_path, *steps):
    return parse_task(task_file_with_plan(TASK, list(steps)), tmp_path / "soup_serving.yaml")


def test_via_and_hold_are_pick_fields(tmp_path):
    plan = _parse(tmp_path, HOLD, SCOOP, {"hand": "left", "pick": "bowl", "place": "table",
                                          "place_offset": [0.27, -0.22], "after": [1]}).demo_plan
    assert plan[0]["hold"] is True and plan[1]["via_times"] == 2


@pytest.mark.parametrize(("step", "expected"), [
    ({**SCOOP, "via": [{"inside": "stove"}]}, r"via\[0\].inside': expected a container from \['bowl', 'ladle', 'pot'\]"),
    ({**SCOOP, "via": [{"over": "ladle"}]}, r"via': expected stops at other objects than 'ladle', the one carried"),
    ({**SCOOP, "via": [{"over": "plate"}]}, r"via\[0\].over': expected an object from \['bowl', 'ladle', 'pot', 'stove'\]"),
    ({**SCOOP, "via": [{"inside": "pot", "over": "bowl"}]}, r"via\[0\]': expected exactly one of inside"),
    ({**SCOOP, "via": [{"offset": [0.1, 0.0]}]}, r"via\[0\]': expected exactly one of inside"),
    ({**SCOOP, "via": [{"over": "bowl", "offest": [0.1, 0.0]}]}, r"via\[0\].offest': expected a field of a via stop"),
    ({**SCOOP, "via": []}, r"via': expected at least 1 item"),
    ({**SCOOP, "via": [{"over": "bowl", "offset": [0.1]}]}, r"via\[0\].offset': expected \[dx, dy\] or \[dx, dy, dz\]"),
    ({k: v for k, v in SCOOP.items() if k != "via"}, r"via_times'.*no via_times without via"),
    ({**SCOOP, "via_times": 0}, r"via_times'.*a whole number of rounds in \[1, 10\]"),
])
def test_bad_stops_are_refused(tmp_path, step, expected):
    with pytest.raises(SpecError, match=rf"soup_serving.yaml: field 'demo_plan\[0\].{expected}"):
        _parse(tmp_path, step)


def _operator(*steps):
    spec = dataclasses.replace(load_task(TASK), demo_plan=list(steps))
    scene = demonstration_scene(spec, EMBODIMENT)
    data, op = home_and_plan(scene)
    return scene, data, op


def test_the_via_point_goes_into_the_pot_and_over_the_bowl_twice():
    """At each stop (the frames the hand stays still in) the ladle's bowl, held as grasped, is over the pot's
    cavity centre VIA_INSIDE_DEPTH_M below its rim, then over the bowl with the ladle's lowest point
    VIA_OVER_CLEARANCE_M above the bowl's top, each shifted by its stop's `offset`: inside, over, inside, over."""
    scene, data, op = _operator(dict(SCOOP))
    frames = op.sides["right"]["timeline"].frames
    closed = next(f for prev, f in zip(frames, frames[1:])        # the pinch closes there, the wrist still
                  if np.allclose(f.pos, prev.pos) and not np.allclose(f.hand, prev.hand))
    ladle, pot, bowl = (scene.object_body_ids[n] for n in ("ladle", "pot", "bowl"))
    rot = data.xmat[ladle].reshape(3, 3)
    held = data.xpos[ladle] - closed.pos                   # the ladle's centre from the wrist, as grasped
    stays = [f for prev, f in zip(frames, frames[1:]) if f.end_step - prev.end_step == VIA_DURATIONS["stay"]
             and np.allclose(f.pos, prev.pos)]
    points = [f.pos + held + rot @ LADLE_BOWL for f in stays]
    assert len(points) == 4
    objects = scene.task.objects
    cavity = data.xpos[pot] + data.xmat[pot].reshape(3, 3) @ np.asarray(objects["pot"].interior_offset)
    rim = data.xpos[pot][2] + objects["pot"].half_extents[2]
    lowest = min((rot @ c)[2] for c in _corners(objects["ladle"].half_extents))     # under the ladle's centre
    dipped, over_bowl = (np.array([*stop.get("offset", [0.0, 0.0]), 0.0][:3]) for stop in SCOOP["via"])   # the plan's shifts
    for inside in points[0::2]:
        assert np.allclose(inside, np.array([*cavity[:2], rim - VIA_INSIDE_DEPTH_M]) + dipped, atol=1e-9)
    for over, stay in zip(points[1::2], stays[1::2]):
        assert np.allclose(over[:2], data.xpos[bowl][:2] + over_bowl[:2], atol=1e-9)
        bottom = stay.pos[2] + held[2] + lowest
        assert bottom == pytest.approx(data.xpos[bowl][2] + objects["bowl"].half_extents[2] + VIA_OVER_CLEARANCE_M
                                       + over_bowl[2])


def _corners(half):
    return [np.array([sx, sy, sz]) * half for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]


def test_a_held_bowl_stays_lifted_in_the_hand_where_planned():
    """`hold: true`: at the end of its step the bowl is held, lifted clear of the table, where the plan puts
    it (the look once it is lifted: pinched by the rim, it sits ~8 cm from where the grasp planned it in
    the hand), and the operator remembers it in the left hand for the hand's next step (direct joint
    path, seed 0)."""
    scene, data, op = _operator(dict(HOLD))
    assert op.held["left"].name == "bowl" and op.held["left"].settle is not None      # kept by the hold
    bowl = scene.object_body_ids["bowl"]
    z0 = float(data.xpos[bowl][2])
    end = op.sides["left"]["timeline"].frames[-2].end_step       # the last frame is the way home
    for step in range(end):
        physics.step_control(scene.model, data, op.act(step, data))
    assert float(data.xpos[bowl][2]) - z0 > 0.03
    assert np.linalg.norm(data.xpos[bowl][:2] - HOLD["place_offset"][:2]) < 0.02


def test_the_carry_from_a_hold_sets_off_from_where_the_look_moved_the_hand():
    """The hand's next pick of a held bowl starts with a frame of its own (the carry raises it): the hold's look
    moves it with the hold's frames, so the carry sets off from where the hand holds the bowl (left where the
    hold was planned, the hand jumped back by the look's correction, ~8 cm, and the pinched bowl fell out)."""
    n = len(_operator(dict(HOLD))[2].sides["left"]["timeline"].frames) - 1    # the hold's frames, then home
    serve = {"hand": "left", "pick": "bowl", "place": "table", "place_offset": [0.27, -0.22]}
    scene, data, op = _operator(dict(HOLD), serve)
    frames = op.sides["left"]["timeline"].frames
    planned = frames[n - 1].pos.copy()
    for step in range(frames[n - 1].end_step):
        physics.step_control(scene.model, data, op.act(step, data))
    assert np.linalg.norm(frames[n - 1].pos[:2] - planned[:2]) > 0.03      # the look moved the hold
    assert np.allclose(frames[n].pos[:2], frames[n - 1].pos[:2], atol=1e-9)
