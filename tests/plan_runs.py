"""Run a planned demonstration part of the way, for tests of plan steps."""

import dataclasses

import numpy as np

from sim import physics
from sim.demo_plan import PlanScope, parse_plan
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task
from teleop.recorder import home
from teleop.scripted_operator import ScriptedOperator


# jigsaw_puzzle_assembly's first step on its paper embodiment, the flat pinch's tests' subject
JIGSAW = ("jigsaw_puzzle_assembly", "iiwa7_sharpa")
JIGSAW_GREEN = {"hand": "right", "pick": "green_piece", "place": "white_piece", "place_offset": [0.108, -0.008, -0.016],
                "grasp": "flat_pinch", "grasp_yaw": 90}
JIGSAW_GREEN_TO_TABLE = {**JIGSAW_GREEN, "place": "table", "place_offset": [0.105, 0.12]}

def rise_through_lift(scene, data, op, name: str, hand: str = "right") -> float:
    """Run the direct joint path until the hand's lift (the first keyframe 10 cm above the one before,
    after the approach: the hand comes down, closes, lifts) and return how far object ``name`` rose (m)."""
    body = scene.object_body_ids[name]
    z0, frames = float(data.xpos[body][2]), op.sides[hand]["timeline"].frames
    lifted = next(f for prev, f in zip(frames[2:], frames[3:]) if f.pos[2] > prev.pos[2] + 0.1).end_step
    for step in range(lifted):
        physics.step_control(scene.model, data, op.act(step, data))
    return float(data.xpos[body][2]) - z0


def home_and_plan(scene, operator=None):
    """``(data, operator)``: the scene at its home pose and a scripted operator (a new ScriptedOperator
    unless given) that has planned its demonstration there."""
    data = home(scene)
    operator = operator or ScriptedOperator()
    operator.reset(scene, data)
    return data, operator


def looks_with_object_under_wrist(op, data, name: str, looks: tuple[str, ...], hand: str = "right",
                                  below_m: float = 0.05) -> None:
    """Run the operator's looks named ``looks`` (on_frame_end adjusts, e.g. "set_off") on ``data`` with
    object ``name`` put ``below_m`` under ``hand``'s wrist, as if held there."""
    import mujoco

    side, model = op.sides[hand], op.scene.model
    adr = model.jnt_qposadr[model.body_jntadr[op.scene.object_body_ids[name]]]
    data.qpos[adr:adr + 3] = data.site_xpos[side["wrist_site_id"]] - [0.0, 0.0, below_m]
    mujoco.mj_forward(model, data)
    for _, adjust in side["looks"]:
        if adjust.__name__ in looks:
            adjust(data)


def parse_steps(task: str, steps: list[dict]):
    """``(spec, plan)``: task ``task``'s spec and ``steps`` parsed as its plan (a bad step raises SpecError)."""
    spec = load_task(task)
    return spec, parse_plan(f"{task}.yaml", {"demo_plan": steps}, PlanScope(spec.objects, spec.zones, spec.points))


def plan_steps_on(task: str, embodiment: str, steps: list[dict], seed: int = 0):
    """``(operator, data)``: ``steps`` planned as task ``task``'s plan on ``embodiment``, demonstration
    seed ``seed``, from the home pose."""
    spec, plan = parse_steps(task, steps)
    scene = demonstration_scene(dataclasses.replace(spec, demo_plan=plan), embodiment, seed)
    data, op = home_and_plan(scene)
    return op, data


def timeline_rows(side: dict) -> list[tuple]:
    """A side's planned keyframes as comparable rows (end step, wrist position and quaternion, hand targets),
    rounded to 1e-9: two plans are the same plan when their rows are equal."""
    return [(f.end_step, *np.round(f.pos, 9), *np.round(f.quat, 9), *np.round(f.hand, 9))
            for f in side["timeline"].frames]


def front_slide_look(side: dict):
    """``(look, slide, lower)``: the one upright look a front place plans outside the opening (teleop/plan_steps/
    upright_look.py), and the slide-in and let-go keyframes that follow it."""
    looks = [(step, fn) for step, fn in side["looks"] if fn.__qualname__.startswith("upright_look")]
    assert len(looks) == 1, "one look, outside the opening"
    step, look = looks[0]
    frames = side["timeline"].frames
    first = next(k for k, f in enumerate(frames) if f.end_step == step) + 1
    return look, frames[first], frames[first + 1]
