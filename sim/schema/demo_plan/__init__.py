"""Schema of a task's `demo_plan` steps: one model per step kind (sim/demo_plan.py picks the kind).

Shapes, types and ranges are declared on the fields. What a step names in its task (an object, a
container, a hinge and its range, a pourer, a task point) is checked by field validators against the
`PlanScope` passed as validation context; a validator that needs another field reads it from the fields
validated before it, so field order matters where noted. Errors name the field (`demo_plan[2].place`)
and what was expected, through the schema layer's messages (sim/schema/messages.py).
An optional field absent from the step takes its planner's default: `= None` in these models means "absent" (a
default is not validated), so an explicit null in the file is refused by the field's type.

One module per step kind; fields.py holds the vocabulary and field types, step.py what kinds share.
"""

from __future__ import annotations

from .fields import (APPROACH_PITCH_RANGE_DEG, BOTH_HANDS, CARRY_RANGE_S, DRAG_CONTACTS, DRAG_HOOK, DRAG_HOOK_DEPTH_M,
                     DRAG_PALM, DRAG_PITCH_DEG, GRASP_YAW_ACROSS, HANDS, OPEN_RANGE_S, PICK_GRASPS, PINCH_FINGERS,
                     PLACE_FROM, PLACE_FROM_FRONT, PLAN_GRASPS, POUR_DEFAULT_GRASP, POUR_DEFAULT_TILT_DEG,
                     POUR_GRASPS, POUR_TILT_RANGE_DEG, PRESS_RANGE_M, SIDE_GRASP, SIDE_ROLL_RANGE_DEG,
                     SLIDE_CLEARANCE_RANGE_M, SQUEEZE_RANGE_M, TABLE_TARGET, TIPS_HEIGHT_RANGE_M, TOE_IN_RANGE_DEG,
                     TURN_SPEED_RANGE_M_S, VIA_KINDS, VIA_TIMES_RANGE, WAIT_RANGE_S)
from .step import PlanStep
from .carry import CarryStep
from .drag import DragStep
from .handover import HandoverStep
from .pick import PickStep
from .pour import PourStep
from .press import PressStep
from .strike import StrikeStep
from .turn import TurnStep

# a step's kind is the one of these fields it has
STEP_MODELS: dict[str, type[PlanStep]] = {
    "pick": PickStep, "drag": DragStep, "pour": PourStep, "press": PressStep, "turn": TurnStep,
    "carry": CarryStep, "strike": StrikeStep, "handover": HandoverStep,
}

__all__ = ("APPROACH_PITCH_RANGE_DEG", "BOTH_HANDS", "CARRY_RANGE_S", "DRAG_CONTACTS", "DRAG_HOOK",
           "DRAG_HOOK_DEPTH_M", "DRAG_PALM", "DRAG_PITCH_DEG", "GRASP_YAW_ACROSS", "HANDS", "OPEN_RANGE_S",
           "PICK_GRASPS", "PINCH_FINGERS", "PLACE_FROM", "PLACE_FROM_FRONT", "PLAN_GRASPS", "POUR_DEFAULT_GRASP",
           "POUR_DEFAULT_TILT_DEG", "POUR_GRASPS", "POUR_TILT_RANGE_DEG", "PRESS_RANGE_M", "SIDE_GRASP",
           "SIDE_ROLL_RANGE_DEG", "SLIDE_CLEARANCE_RANGE_M", "SQUEEZE_RANGE_M", "TABLE_TARGET", "TIPS_HEIGHT_RANGE_M",
           "TOE_IN_RANGE_DEG", "TURN_SPEED_RANGE_M_S", "VIA_KINDS", "VIA_TIMES_RANGE", "WAIT_RANGE_S", "CarryStep",
           "DragStep", "HandoverStep", "PickStep", "PourStep", "PressStep", "StrikeStep", "TurnStep", "PlanStep",
           "STEP_MODELS")
