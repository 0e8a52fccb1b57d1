"""Evaluation rollouts of the privileged scripted baseline through the policy interface: the stream
interface by default, labelled rows, and an unknown operator named before anything runs."""

import pytest

from policies.rollouts import rollout_seed, run_rollouts
from policies.scripted_baseline import ScriptedBaseline
from teleop.demos import OPERATORS

SETTING = ("citrus_plate_loading", "ur5_rh5dg2")


def test_an_unknown_operator_fails_fast_naming_the_valid_ones():
    with pytest.raises(ValueError, match="operator: expected one of .*'stream'.*'scripted'"):
        ScriptedBaseline("joystick")


@pytest.mark.parametrize("operator", sorted(OPERATORS))
def test_rollouts_are_labelled_rows_at_their_own_seeds(operator):
    rows = run_rollouts(ScriptedBaseline(operator), *SETTING, "inv_equi", [], 2, max_steps=20)
    assert [r["episode"] for r in rows] == [0, 1]
    assert [r["seed"] for r in rows] == [rollout_seed(SETTING[0], "inv_equi", i) for i in range(2)]
    assert all(r["termination"] != "error" and r["anchor"] is None and not r["success"] for r in rows)
    assert {r["operator"] for r in rows} == {operator}
    # the runner counts control steps and queries: the baseline is queried every control step
    assert all(r["control_steps"] == r["n_steps"] == r["policy_queries"] == 20 for r in rows)


def test_by_default_the_scripted_operator_rolls_out_through_the_stream_interface():
    rows = run_rollouts(ScriptedBaseline(), *SETTING, "inv_equi", [], 1, max_steps=5)
    assert rows[0]["operator"] == "stream" and rows[0]["policy"] == "scripted_operator"
