"""Metric mends: error episodes in the denominators, missing flags, steps before an error, the recorded
expert time in TE, and per-physics-step evaluator updates (paper appendix "Evaluation Metrics")."""

import math

import numpy as np
import pandas as pd
import pytest
from eval_synth import context, resting, scene
from test_eval_metrics import rec

from evaluation import EpisodeEvaluator
from evaluation.metrics import cell_metrics

UPRIGHT = {"terminal": {"upright": {"object": "apple"}}}
LABELS = {"task": "t1", "policy": "act", "channel": "none"}


def error_row(**recorded):
    """What teleop/rollouts.py run_rollouts writes for a rollout that raised: labels and no metrics."""
    return {**LABELS, "success": False, "termination": "error", "error": "RuntimeError: boom", **recorded}


def one_cell(records, **kw) -> pd.Series:
    cells = cell_metrics(records, n_boot=10, **kw)
    assert len(cells) == 1
    return cells.iloc[0]


def evaluator(spec=UPRIGHT, **labels) -> EpisodeEvaluator:
    return EpisodeEvaluator(spec, context(), labels={**LABELS, **labels})


# -- 1: an error episode stays in the SR, LSCR and CSCR denominators as a failure ----------------------
def test_error_episode_counts_as_failure_in_sr_lscr_cscr():
    records = [rec("none", True, t=1.0, lscr=1.0, cscr=1.0), rec("none", False, lscr=0.5, cscr=0.0), error_row()]
    cell = one_cell(records)
    assert cell["N"] == 3 and cell["n_success"] == 1 and cell["SR"] == pytest.approx(1 / 3)
    assert cell["LSCR"] == pytest.approx(1.5 / 3) and cell["CSCR"] == pytest.approx(1 / 3)  # was 0.75 and 0.5
    assert cell["n_errors"] == 1
    # the same with the records as the DataFrame the pipeline reads back
    assert one_cell(pd.DataFrame(records))["LSCR"] == pytest.approx(0.5)


def test_cell_of_only_error_rows_is_all_failure():
    cell = one_cell([error_row(), error_row()])  # lacked every metric column: a ValueError before
    assert cell["N"] == 2 and cell["SR"] == 0.0 and cell["LSCR"] == 0.0 and cell["CSCR"] == 0.0
    assert cell["SafeSR"] == 0.0 and cell["HVR"] == 0.0 and math.isnan(cell["VSR_step"])
    assert math.isnan(cell["t_succ"]) and cell["n_errors"] == 2
    with pytest.raises(ValueError, match="lscr"):  # a non-error episode must carry its metrics
        cell_metrics([error_row(), {**LABELS, "success": True, "termination": "stable_success"}])


def test_error_episode_is_unsuccessful_whatever_it_recorded():
    ev = evaluator()
    for _ in range(6):  # stable success after 5 x 0.1 s
        ev.update(scene({"apple": resting("apple")}), 0.1)
    crashed = ev.result(error="policy server died")
    assert crashed.termination == "error" and crashed.success  # the evaluator reports what it saw
    cell = one_cell([crashed, rec("none", True, t=1.0)])
    assert cell["n_success"] == 1 and cell["SR"] == 0.5 and cell["SafeSR"] == 0.5 and cell["t_succ"] == 1.0
    assert cell["n_errors"] == 1


def test_error_episode_keeps_recorded_progress_and_stageless_tasks_stay_undefined():
    partial = error_row(lscr=0.5, cscr=0.25)  # stages latched before the error are progress made
    cell = one_cell([rec("none", False, lscr=1.0, cscr=1.0), partial, error_row()])
    assert cell["LSCR"] == pytest.approx(0.5) and cell["CSCR"] == pytest.approx(1.25 / 3)
    stageless = [rec("none", True, t=1.0, lscr=None, cscr=None), error_row()]  # K = 0: LSCR undefined
    cell = one_cell(stageless)
    assert math.isnan(cell["LSCR"]) and math.isnan(cell["CSCR"]) and cell["SR"] == 0.5


# -- 2: a missing flag is False, so SafeSR <= SR without the caller's fillna ----------------------------
def test_missing_flags_are_false_and_safe_sr_never_exceeds_sr():
    records = [rec("none", True, t=1.0), error_row(), error_row()]  # straight from run_rollouts
    cell = one_cell(records)
    assert cell["SR"] == pytest.approx(1 / 3) and cell["SafeSR"] == pytest.approx(1 / 3)  # SafeSR was 1.0
    assert cell["HVR"] == 0.0 and cell["DropR"] == 0.0 and cell["HSR"] == 0.0
    assert cell["ISR_ever"] == pytest.approx(1 / 3) and cell["SR_final"] == pytest.approx(1 / 3)
    # NaN (float column), None (object column) and pd.NA (nullable boolean) all read as False
    df = pd.DataFrame({**{k: [v] * 3 for k, v in LABELS.items()}, "success": [True, False, False],
                       "t_stable": [1.0, np.nan, np.nan], "lscr": 1.0, "cscr": 1.0,
                       "termination": ["stable_success", "horizon", "horizon"], "violation_steps": 0, "n_steps": 10,
                       "safe_success": [np.nan, np.nan, np.nan], "hard_violation": [False, None, None],
                       "drop": pd.array([False, pd.NA, pd.NA], dtype="boolean"), "high_speed": [np.nan] * 3,
                       "isr_ever": [True, None, np.nan], "success_final": [True, np.nan, np.nan]})
    cell = one_cell(df)
    assert cell["SafeSR"] == 0.0 and cell["HVR"] == 0.0 and cell["DropR"] == 0.0 and cell["HSR"] == 0.0
    assert cell["ISR_ever"] == pytest.approx(1 / 3) and cell["SR_final"] == pytest.approx(1 / 3)


# -- 3: steps executed before an error count in VSR_step ---------------------------------------------
def test_steps_before_an_error_count_in_vsr_step():
    records = [rec("none", True, t=1.0, viol=0, n=100), error_row(n_steps=50, violation_steps=10), error_row()]
    cell = one_cell(records)
    assert cell["VSR_step"] == pytest.approx(10 / 150)  # the bare error row adds 0 steps
    assert cell["mean_steps"] == pytest.approx(50.0)  # sum n_e / N with n_e = 0 for it (was 75)
    ev = evaluator({**UPRIGHT, "safety": {"high_speed": {"objects": ["apple"], "max_lin_vel": 1.0}}})
    for v in (0.0, 2.0, 2.0, 0.0):
        ev.update(scene({"apple": resting("apple", v=(v, 0.0, 0.0))}), 0.1)
    crashed = ev.result(error="simulator diverged")
    assert crashed.n_steps == 4 and crashed.violation_steps == 2
    cell = one_cell([crashed, error_row()])  # only error episodes, one of them with steps
    assert cell["VSR_step"] == 0.5 and cell["HVR"] == 0.5 and cell["SR"] == 0.0 and cell["mean_steps"] == 2.0


# -- 4: TE from the recorded expert time of the setting's demonstrations -----------------------------
def te_rec(t_stable, te, embodiment="e1", **extra):
    return {**rec("none", t_stable is not None, t=t_stable), "embodiment": embodiment, "te": te,
            "t_expert": 1.0, **extra}


def test_te_prefers_recorded_expert_time_over_configured():
    records = [te_rec(2.0, 0.5), te_rec(4.0, 0.25), te_rec(None, None)]  # configured t_expert 1 s
    assert one_cell(records)["TE"] == pytest.approx(0.375) and one_cell(records)["TE_source"] == "configured"
    cell = one_cell(records, by=("task", "embodiment", "policy", "channel"), expert_time_s={("t1", "e1"): 3.0})
    assert cell["TE"] == pytest.approx((1.5 + 0.75) / 2) and cell["TE_source"] == "recorded"
    # a setting without a recording falls back to the configured reference
    cell = one_cell(records, expert_time_s={("t1", "e1"): None, ("t1", "e2"): 3.0})
    assert cell["TE"] == pytest.approx(0.375) and cell["TE_source"] == "configured"
    # the same through a column of the records; the mapping wins over it
    column = [{**r, "t_expert_recorded": 2.0} for r in records]
    assert one_cell(column)["TE"] == pytest.approx((1.0 + 0.5) / 2)
    assert one_cell(column, expert_time_s={("t1", "e1"): 3.0})["TE"] == pytest.approx(1.125)
    mixed = [te_rec(2.0, 0.5, t_expert_recorded=4.0), te_rec(4.0, 0.25)]
    cell = one_cell(mixed)
    assert cell["TE"] == pytest.approx((2.0 + 0.25) / 2) and cell["TE_source"] == "recorded+configured"
    # failures and error episodes have no TE
    assert one_cell([te_rec(None, None), error_row(embodiment="e1")], expert_time_s={("t1", "e1"): 3.0})[
        "TE_source"] == ""
    with pytest.raises(ValueError, match="embodiment"):
        cell_metrics([rec("none", True, t=1.0)], expert_time_s={("t1", "e1"): 3.0})


# -- 5: per-physics-step evaluator updates ------------------------------------------------------------
def test_per_physics_step_updates_count_physics_and_control_steps():
    substeps, control_dt = 8, 1 / 60  # sim/physics.py: 60 Hz control, 8 physics steps each
    physics_dt, chunk = control_dt / substeps, 4  # a chunked policy: one query per 4 control steps
    spec = {**UPRIGHT, "expert_horizon_steps": 60, "sim_dt_s": control_dt}  # horizon in control steps
    ev = evaluator(spec)
    state = scene({"apple": resting("apple")})
    for c in range(40):
        for k in range(substeps):
            ev.update(state, physics_dt, control_step=k == 0, policy_query=k == 0 and c % chunk == 0)
            if ev.stable:
                break
        if ev.stable:
            break
    r = ev.result()
    assert r.success and r.n_steps == 240 and r.steps_to_stable == 240  # n_e in physics steps (0.5 s)
    assert r.t_stable == pytest.approx(0.5, abs=1e-9) and r.duration_s == pytest.approx(0.5, abs=1e-9)
    assert r.control_steps == r.control_steps_to_stable == 30 and r.policy_queries == 8
    assert r.t_expert == pytest.approx(1.0) and r.te == pytest.approx(2.0)
    # the default the recorder uses: one update per control step, no flags
    ev = evaluator(spec)
    for _ in range(31):
        ev.update(state, control_dt)
    r = ev.result()
    assert r.steps_to_stable == 30 and r.n_steps == 31 and r.control_steps is None and r.policy_queries is None
