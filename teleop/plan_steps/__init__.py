"""The scripted operator's planners, one per plan step kind (sim/demo_plan.py STEP_KINDS): each
appends the step's wrist keyframes and hand targets to its hand's timeline."""

from teleop.plan_steps import carry, drag, pick_place, pour, press, strike, turn

PLANNERS = {"pick": pick_place.plan, "drag": drag.plan, "pour": pour.plan, "press": press.plan, "turn": turn.plan,
             "carry": carry.plan, "strike": strike.plan}
