"""The scripted operator's planners, one per plan step kind (sim/demo_plan.py STEP_KINDS): each
appends the step's wrist keyframes and hand targets to its hand's timeline."""

from teleop.plan_steps import carry, drag, handover, held, pick, pour, press, strike, turn
from teleop.plan_steps import via      # a pick through waypoints, or kept in the hand

# a pick with via stops or hold: true is via's; of an object handed over, held's; else pick's (any: return_home,
# and round_pinch as its hand file declares)
PLANNERS = {"pick": pick.as_declared(pick.returning(via.planner(held.planner(pick.plan)))), "drag": drag.plan,
            "pour": pour.plan,
            "press": press.plan, "turn": turn.plan, "carry": carry.plan, "strike": strike.plan,
            "handover": handover.plan}
