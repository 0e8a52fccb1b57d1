"""`handover` (one hand gives an object to the other in the air), `pick_from: front` (an upright bottle
taken out level through a fridge's open side) and what a hand keeps between steps (`hold: true` on a
pour; a step naming what its hand holds starts from holding it): the plan checks, the planned
timelines, and a real take-out of the 1.2 kg wine bottle from the fridge."""

import dataclasses

import numpy as np
import pytest

from sim import physics
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import parse_task
from teleop.plan_steps.held import planner

from task_files import task_file_with_plan
from plan_runs import home_and_plan

TASK, EMBODIMENT = "fridge_wine_interhand_pour", "ur5_rh5dg2"
# the left takes the bottle out by its neck, the right takes its body, palm turned partly up
GIVE = {"hand": "left", "handover": "wine_bottle", "to_hand": "right", "at": [0.0, -0.12, 0.3], "pick_from": "front",
        "grasp": "side", "grasp_point": [0.0, 0.0, 0.1], "take_point": [0.0, 0.0, -0.08], "take_roll_deg": 120}
POUR = {"hand": "right", "pour": "wine_bottle", "into": "glass", "hold": True}
BACK = {"hand": "right", "handover": "wine_bottle", "to_hand": "left", "at": [0.0, -0.12, 0.3],
        "take_point": [0.0, 0.0, 0.1]}
PUT = {"hand": "left", "pick": "wine_bottle", "place": "fridge", "place_from": "front", "place_offset": [0.0, 0.02]}


def _task(steps, tmp_path, door=True):
    task = parse_task(task_file_with_plan(TASK, steps), tmp_path / "fridge_wine.yaml")
    if not door:        # the fridge standing open: the take-out alone, without the door's turn first
        objects = dict(task.objects)
        objects["fridge"] = dataclasses.replace(objects["fridge"], links=())
        task = dataclasses.replace(task, objects=objects)
    return task


def _planned(steps, tmp_path, door=True):
    scene = demonstration_scene(_task(steps, tmp_path, door), EMBODIMENT)
    data, op = home_and_plan(scene)
    return scene, data, op


def test_a_handover_chain_parses(tmp_path):
    plan = _task([GIVE, POUR, BACK, PUT], tmp_path).demo_plan
    assert [plan[0]["to_hand"], plan[1]["hold"], plan[2]["to_hand"]] == ["right", True, "left"]


@pytest.mark.parametrize(("step", "expected"), [
    ({**GIVE, "to_hand": "left"}, r"to_hand'.*'right' \(the other hand\)"),
    ({**GIVE, "grasp": "power", "grasp_point": None}, r"pick_from'.*only with grasp: side"),
    ({**GIVE, "at": [0.0, 0.3]}, r"at'.*\[x, y, z\] of the table top"),
    ({**GIVE, "take_roll_deg": 150}, r"take_roll_deg'.*degrees in \[60, 135\]"),
    ({**GIVE, "grasp_closure": 2.0}, r"grasp_closure'.*a factor in \[1, 1.5\]"),
    ({**GIVE, "handover": "sofa"}, r"handover'.*an object from \['fridge', 'glass', 'wine_bottle'\]"),
    ({**POUR, "hold": 1}, r"hold'"),
])
def test_a_handover_and_a_hold_are_checked(tmp_path, step, expected):
    step = {k: v for k, v in step.items() if v is not None}
    with pytest.raises(SpecError, match=rf"fridge_wine.yaml: field 'demo_plan\[0\].{expected}"):
        parse_task(task_file_with_plan(TASK, [step]), tmp_path / "fridge_wine.yaml")


def _opened(frames, side) -> int:
    return next(k for k in range(1, len(frames)) if np.array_equal(frames[k].hand, side["open"])
                and not np.array_equal(frames[k - 1].hand, side["open"]))


def test_the_giver_lets_go_only_once_the_taker_has_closed(tmp_path):
    """The taking hand closes beside the handover point while the giving hand holds still there; the giver
    opens only after the taker's closing has ended, and the taker holds still until the giver is off."""
    scene, data, op = _planned([GIVE], tmp_path, door=False)
    left, right = op.sides["left"], op.sides["right"]
    lf, rf = left["timeline"].frames, right["timeline"].frames
    closed = next(f for f in rf if np.allclose(f.hand, op.power(right, (1.0, 1.0))))
    opened = lf[_opened(lf, left)]
    assert opened.end_step - 20 >= closed.end_step             # DURATIONS["open"] = 20: opening starts after
    held = [f for f in lf if f.end_step <= opened.end_step - 20 and f.end_step >= closed.end_step - 90]
    assert all(np.allclose(f.pos, held[0].pos) for f in held)  # the giver holds still while the taker closes
    at = np.array(GIVE["at"]) + [0.0, 0.0, scene.table_height]
    assert list(op.held) == ["right"] and op.held["right"].name == "wine_bottle"
    assert np.allclose(closed.pos + op.held["right"].offset, at, atol=1e-9)     # the taker closes round it there


def test_steps_after_a_handover_start_from_holding(tmp_path):
    """The pour and the hand-back after a handover do not grasp again: the right hand never goes near the
    fridge; the left puts the bottle back in through the front from holding it; nothing is held at the end."""
    scene, data, op = _planned([GIVE, POUR, BACK, PUT], tmp_path)
    fridge_front_y = data.xpos[scene.object_body_ids["fridge"]][1] - 0.17
    assert all(f.pos[1] < fridge_front_y for f in op.sides["right"]["timeline"].frames)
    assert op.held == {}
    # without the memory of what is held, the hand-back would be a plain pick of the bottle where it stands
    calls = []
    planned = planner(lambda op_, data_, item: calls.append(item))
    op.held = {}
    planned(op, data, dict(PUT))
    assert calls                                    # nothing held: pick's own planner


def _run(scene, data, op, steps: int) -> None:
    for step in range(steps):
        physics.step_control(scene.model, data, op.act(step, data))


def test_a_bottle_is_taken_out_of_the_fridge_through_its_front(tmp_path):
    """The left hand comes in level through the open front, takes the 1.2 kg bottle by its neck from the
    side and slides it out: lifted off the cavity floor and clear of the fridge's front (direct joint path,
    seed 0)."""
    scene, data, op = _planned([GIVE], tmp_path, door=False)
    bottle = scene.object_body_ids["wine_bottle"]
    z0 = float(data.xpos[bottle][2])
    front = data.xpos[scene.object_body_ids["fridge"]][1] - 0.17
    frames = op.sides["left"]["timeline"].frames
    out = next(f for prev, f in zip(frames, frames[1:]) if f.pos[1] < front - 0.1 < prev.pos[1]).end_step
    _run(scene, data, op, out)
    assert data.xpos[bottle][1] < front - 0.05 and data.xpos[bottle][2] > z0 + 0.01
    assert data.xmat[bottle][8] > 0.9              # still upright in the hand


def test_the_bottle_stays_in_the_taking_hand_once_the_giver_lets_go(tmp_path):
    """Handed over in the air: once the left hand has opened and drawn back, the 1.2 kg bottle hangs in the
    right hand, upright, where it was handed over (direct joint path, seed 0)."""
    scene, data, op = _planned([GIVE], tmp_path, door=False)
    right = op.sides["right"]
    _run(scene, data, op, right["timeline"].frames[-2].end_step)     # the taker holding, the giver off it
    bottle = scene.object_body_ids["wine_bottle"]
    assert data.xpos[bottle][2] - scene.table_height > 0.25 and data.xmat[bottle][8] > 0.9
    assert np.linalg.norm(data.xpos[bottle] - data.site_xpos[right["wrist_site_id"]]) < 0.15


def test_a_pour_from_the_other_hands_bottle_needs_a_place_or_a_hold(tmp_path):
    """A bottle handed over has no place of its own to go back to: a pour that neither keeps it nor names
    place_offset is refused when the operator plans it."""
    with pytest.raises(SpecError, match="sets it down at place_offset"):
        _planned([GIVE, {k: v for k, v in POUR.items() if k != "hold"}], tmp_path, door=False)


@pytest.mark.parametrize(("embodiment", "tabletop"), [("ur5_wuji", True), ("ur5_schunk", False)])
def test_grasp_closure_closes_a_tabletop_grasp_further(tmp_path, embodiment, tabletop):
    """`grasp_closure` takes the giver's declared tabletop grasp that many times as far from open, within the
    actuators' ranges (the Wuji's closed round the bottle's neck untouched); a power grasp is left as it is."""
    task = _task([{**GIVE, "grasp_closure": 1.3}], tmp_path)
    data, op = home_and_plan(demonstration_scene(task, embodiment))
    left = op.sides["left"]
    # the giver's most closed keyframe: the neck grasp's
    held = max((f.hand for f in left["timeline"].frames), key=lambda hand: float(np.abs(hand - left["open"]).sum()))
    assert left["tabletop"] is tabletop
    lo, hi = op.scene.model.actuator_ctrlrange[left["hand_ids"]].T
    expected = np.clip(left["open"] + 1.3 * (left["closed"] - left["open"]), lo, hi) if tabletop else left["closed"]
    np.testing.assert_allclose(held, expected)


def _frames(steps, tmp_path, embodiment):
    data, op = home_and_plan(demonstration_scene(_task(steps, tmp_path), embodiment))
    return [(f.end_step, *f.pos, *f.quat, *f.hand)
            for side in sorted(op.sides) for f in op.sides[side]["timeline"].frames]


@pytest.mark.parametrize(("embodiment", "body"), [("ur5_shadow", True), ("ur5_rh5dg2", False)])
def test_body_hold_takes_the_place_of_the_take_on_a_hand_that_holds_by_the_body(tmp_path, embodiment, body):
    """A handover's `body_hold` (take_point, take_roll_deg) is planned instead of the step's own on an embodiment
    whose hand file declares `heavy_side_hold: body` (the Shadow's); other hands plan the step as written."""
    hold = {"take_point": [0.0, 0.0, -0.035], "take_roll_deg": 100}
    planned = _frames([{**GIVE, "body_hold": hold}], tmp_path, embodiment)
    assert planned == _frames([{**GIVE, **hold}] if body else [GIVE], tmp_path, embodiment)
    assert planned != _frames([GIVE] if body else [{**GIVE, **hold}], tmp_path, embodiment)
