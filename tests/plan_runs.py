"""Run a planned demonstration part of the way, for tests of plan steps."""

from sim import physics
from teleop.recorder import home
from teleop.scripted_operator import ScriptedOperator


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
