"""Plan step `turn`, field `withdraw_past_end` (opt-in, default false): once it lets go, the hand moves out
along the link, level, until it is past the link's free end, and goes on from there round that end instead
of rising over the link: with home on the link's other side it turns about the hinge, past the end, until the
whole hand is off the link's face on that side, and goes home from there. On fridge_fruit_shelf_sorting the
right hand pulls its door open past square and ends on the door's outer side; rising over the door left the
forearm behind the hand across the door's top, and the way home shoved the door back (straight home from past
the end, with the fridge turned -8 degrees, the fingers crossed the door and shoved it shut)."""

import numpy as np
import pytest
import yaml

from sim import physics
from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample, demonstration_seed
from sim.tasks import load_task, parse_task
from teleop.plan_steps.turn import Hinge
from plan_runs import home_and_plan

TASK, SHADOW, DOOR = "fridge_fruit_shelf_sorting", "ur5_shadow", "fridge/right_door"
PULL = {"hand": "right", "turn": DOOR, "to": 1.9, "speed": 0.15}
STEPS = 600                 # the pull ends by ~400 control steps; the way home takes the next 100


def _scene(tmp_path, **fields):
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    # the hand's next step (shutting it again) waits 10 s: without one, the plan's end sends every hand home
    raw["demo_plan"] = [{**PULL, **fields}, {**PULL, "to": 0.0, "wait_s": 10.0}]
    raw.pop("demo_plan_draft", None)
    task = parse_task(raw, tmp_path / "fridge.yaml")
    scene = build_scene(task, SHADOW, demonstration_sample(task, demonstration_seed(TASK, 0)))
    return scene, *home_and_plan(scene)


@pytest.mark.parametrize("value", ["yes", 1, None])
def test_check_refuses_a_withdraw_past_end_that_is_not_a_flag(value):
    task = load_task(TASK)
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.withdraw_past_end"):
        parse_plan("t.yaml", {"demo_plan": [{**PULL, "withdraw_past_end": value}]},
                   PlanScope(task.objects, task.zones, task.points))


def test_the_hand_moves_out_level_past_the_doors_free_end(tmp_path):
    _, _, plain = _scene(tmp_path)
    scene, data, out = _scene(tmp_path, withdraw_past_end=True)
    P, O = plain.sides["right"]["timeline"].frames, out.sides["right"]["timeline"].frames
    i = next(k for k, (p, o) in enumerate(zip(P, O)) if not np.allclose(p.pos, o.pos))
    assert all(p.end_step == o.end_step for p, o in zip(P[:i], O[:i])), "the same pull up to letting go"
    assert P[i].pos[2] > P[i - 1].pos[2] + 0.1, "plain: the hand rises off the door"
    assert abs(O[i].pos[2] - O[i - 1].pos[2]) < 1e-9, "withdrawn: level"
    door = Hinge(scene.model, data, DOOR)
    inside, past = (float(np.linalg.norm(door.radial_vec(f.pos))) for f in (O[i - 1], O[i]))
    assert inside < door.reach() < past, "the wrist from over the bar to past the door's free end"


def test_the_hand_goes_round_the_doors_free_end_to_homes_side(tmp_path):
    _, _, plain = _scene(tmp_path)
    scene, data, out = _scene(tmp_path, withdraw_past_end=True)
    P, O = plain.sides["right"]["timeline"].frames, out.sides["right"]["timeline"].frames
    i = next(k for k, (p, o) in enumerate(zip(P, O)) if not np.allclose(p.pos, o.pos))
    door = Hinge(scene.model, data, DOOR)
    rounding = []
    for frame in O[i + 1:]:
        if np.linalg.norm(door.radial_vec(frame.pos)) < door.reach() or abs(frame.pos[2] - O[i].pos[2]) > 1e-9:
            break
        rounding.append(frame)
    assert rounding, "level round the end, past it"
    # off the plane through the hinge and where the hand withdrew to: the door, pulled open, and home lie on
    # one side; the hand ends beyond every corner of the door on that side
    normal = np.cross(door.axis, door.radial(O[i].pos))
    home = out.sides["right"]["home"][0]
    towards = np.sign(normal @ (home - door.anchor))
    door_reach = max(towards * normal @ (door.rotated(c, PULL["to"] - door.angle) - door.anchor)
                     for g in door.geoms for c in door._corners(g))
    assert towards * normal @ (rounding[-1].pos - door.anchor) > door_reach


def _door_after_the_way_home(tmp_path, **fields) -> float:
    scene, data, op = _scene(tmp_path, **fields)
    for step in range(STEPS):
        physics.step_control(scene.model, data, op.act(step, data))
    return float(data.qpos[scene.model.jnt_qposadr[scene.model.joint(DOOR).id]])


def test_the_door_stays_open_when_the_hand_goes_home_round_its_end(tmp_path):
    assert _door_after_the_way_home(tmp_path, withdraw_past_end=True) > 1.65
    assert _door_after_the_way_home(tmp_path) < 1.6, "over the door, the arm shoves it back"
