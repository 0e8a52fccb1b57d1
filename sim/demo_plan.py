"""A task's `demo_plan`: what the scripted operator (teleop/scripted_operator.py) does, step by step.

Each step is one kind, named by the field that says what it acts on: `pick` (carry an object to a
target), `drag` (pull a container into a zone), `pour` (tip a bottle's mouth over a target), `press`
(press keys or buttons in order), `turn` (swing a lid or a door to a joint angle), `carry` (both hands
carry an object between their palms), `strike` (hit a target once with a tool, then put the tool away),
`handover` (one hand gives an object to the other in the air).
Every field is checked when the task loads by the step kind's schema (sim/schema/demo_plan/), so a
bad plan fails then, naming the step and the field. A new kind is a new model there and a planner in
teleop/plan_steps/.
"""

from __future__ import annotations

from dataclasses import dataclass

from sim.errors import SpecError
from sim.schema.base import validate
# the plan's vocabulary, used by the planners (teleop/plan_steps/)
from sim.schema.demo_plan import (BOTH_HANDS, DRAG_HOOK_DEPTH_M, DRAG_PALM, DRAG_PITCH_DEG, GRASP_YAW_ACROSS,  # noqa: F401
                                  PLACE_FROM_FRONT, POUR_DEFAULT_GRASP, POUR_DEFAULT_TILT_DEG, SIDE_GRASP,
                                  STEP_MODELS, TABLE_TARGET)

PLAN_STEP = " or ".join(
    "{" + ", ".join([*(f for f, info in model.model_fields.items() if info.is_required()), "..."]) + "}"
    for model in STEP_MODELS.values())


@dataclass(frozen=True)
class PlanScope:
    """What a plan step may name: the task's objects (name -> ObjectSpec), zones and points."""
    objects: dict
    zones: dict
    points: dict


def step_kind(step: dict) -> str:
    """The kind of a (checked) plan step: the one STEP_MODELS key among its fields."""
    return next(kind for kind in STEP_MODELS if kind in step)


def parse_plan(path, raw: dict, scope: PlanScope) -> list[dict]:
    """The task's `demo_plan`, every step checked; the steps are returned as written (the planners read
    their fields with the defaults in sim/schema/demo_plan/)."""
    plan = raw.get("demo_plan") or []
    if not isinstance(plan, list):
        raise SpecError(path, "demo_plan", f"a list of steps {PLAN_STEP}", plan)
    for i, step in enumerate(plan):
        where = f"demo_plan[{i}]"
        kinds = [k for k in STEP_MODELS if isinstance(step, dict) and k in step]
        if len(kinds) != 1:
            raise SpecError(path, where, f"a mapping with exactly one of {', '.join(map(repr, STEP_MODELS))}: "
                                         f"{PLAN_STEP}", step)
        validate(STEP_MODELS[kinds[0]], step, path, prefix=where, context={"scope": scope, "index": i})
    return plan
