"""Pick field `open_s`: how long the hand opens over the place before it rises (default DURATIONS["open"]).
On canned_food_tray_arrangement the RH56DFX's index and little fingers stay wedged either side of the
6.4 cm MSG jar as the hand opens; rising after the default third of a second, the hand lifted the jar out of
the tray and tipped it over. The check refuses a value out of (0, 3] s; without the field nothing changes."""

import numpy as np
import pytest

from sim.errors import SpecError
from teleop.operator_motion import DURATIONS
from plan_runs import parse_steps, plan_steps_on

TASK, EMBODIMENT = "canned_food_tray_arrangement", "ur5_rh56dfx"
MSG = {"hand": "left", "pick": "msg", "place": "tray", "place_offset": [-0.1, -0.07, -0.024]}


@pytest.mark.parametrize("value", [0, -1, 4, "slow"])
def test_the_check_refuses_open_s_out_of_range(value):
    with pytest.raises(SpecError, match=r"field 'demo_plan\[0\]\.open_s'"):
        parse_steps(TASK, [{**MSG, "open_s": value}])


def test_open_s_holds_the_opening_hand_over_the_place_that_long():
    """With open_s: 1 the keyframe that opens the hand lasts 60 control steps rather than 20, the wrist
    staying where it let go; every keyframe before it is unchanged and every later one 40 steps later."""
    default, slow = (plan_steps_on(TASK, EMBODIMENT, [step])[0].sides["left"]["timeline"].frames
                     for step in (MSG, {**MSG, "open_s": 1}))
    assert len(slow) == len(default)
    opened = [i for i, f in enumerate(default) if i and np.allclose(f.hand, 0.0) and not np.allclose(default[i - 1].hand, 0.0)]
    i = opened[-1]      # the release (the last keyframe that opens a closed hand)
    assert [f.end_step for f in slow[:i]] == [f.end_step for f in default[:i]]
    assert slow[i].end_step - slow[i - 1].end_step == 60
    assert default[i].end_step - default[i - 1].end_step == DURATIONS["open"]
    assert np.allclose(slow[i].pos, slow[i - 1].pos)
    assert all(s.end_step - d.end_step == 60 - DURATIONS["open"] for s, d in zip(slow[i:], default[i:]))
