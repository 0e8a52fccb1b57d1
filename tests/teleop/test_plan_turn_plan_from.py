"""`turn`'s opt-in `plan_from`: a turn planned from a given angle, not from where earlier steps leave the link. A
second shut of a door the first shut left ajar (fridge_fruit_shelf_sorting's right door on the UR5+Schunk, 0.23 rad:
reaching over the door at its stop, the palm lands on its top) plans nothing without it (the plan has the door shut);
with it and `start_look` the hand meets the door where it really is."""

import numpy as np
import pytest

from sim.errors import SpecError
from teleop.plan_steps.turn import ARC_STEP_RAD
from plan_runs import parse_steps, plan_steps_on

TASK, EMB, LEVER = "faucet_cup_water_fill", "rm65_revo2", "faucet/handle"
OPEN = {"hand": "right", "turn": LEVER, "to": 1.4, "speed": 0.05}
SHUT = {"hand": "right", "turn": LEVER, "to": 0.0, "speed": 0.05, "after": [0]}
AGAIN = {**SHUT, "after": [1]}
FROM = 0.3


def test_a_second_shut_plans_only_with_plan_from():
    once, _ = plan_steps_on(TASK, EMB, [OPEN, SHUT])
    twice, _ = plan_steps_on(TASK, EMB, [OPEN, SHUT, AGAIN])
    again, _ = plan_steps_on(TASK, EMB, [OPEN, SHUT, {**AGAIN, "plan_from": FROM}])
    frames = [f.end_step for f in once.sides["right"]["timeline"].frames]
    assert [f.end_step for f in twice.sides["right"]["timeline"].frames] == frames     # planned shut: nothing to do
    more = again.sides["right"]["timeline"].frames
    # the steps before it are as planned; it adds its own (the arc from FROM to 0 and the way there and back)
    assert [f.end_step for f in more[:len(frames)]] == frames
    assert len(more) - len(frames) >= int(np.ceil(FROM / ARC_STEP_RAD)) + 1


def test_plan_from_lies_within_the_joint_range():
    parse_steps(TASK, [OPEN, {**SHUT, "plan_from": FROM}])
    with pytest.raises(SpecError):
        parse_steps(TASK, [OPEN, {**SHUT, "plan_from": 2.0}])
