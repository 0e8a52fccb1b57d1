"""Episodes run at most 1.5x the task's expert horizon (paper), whichever spelling the task uses."""

from sim.tasks import load_task
from teleop.recorder import NO_EXPERT_HORIZON_STEPS, evaluation_horizon


def test_horizon_is_one_and_a_half_expert_horizons():
    assert evaluation_horizon({"expert_horizon_steps": 1500}) == 2250
    assert evaluation_horizon({"expert_time_step": 101}) == 151
    assert evaluation_horizon({}) == NO_EXPERT_HORIZON_STEPS


def test_every_task_declares_an_expert_horizon():
    from sim.registry import names

    missing = [t for t in names("tasks") if evaluation_horizon(load_task(t).metrics) == NO_EXPERT_HORIZON_STEPS]
    assert not missing
