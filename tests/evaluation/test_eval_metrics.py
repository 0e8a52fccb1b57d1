"""Cell metrics, bootstrap CI and channel robustness on a hand-computed example."""

import math

import numpy as np
import pandas as pd
import pytest
from eval_synth import context, resting, scene

from evaluation import evaluate_states
from evaluation.metrics import bootstrap_ci, cell_metrics, channel_robustness, task_macro


def rec(channel, success, t=None, lscr=1.0, cscr=1.0, drop=False, high=False, viol=0, n=100, isr=None,
        final=None, task="t1", policy="act"):
    return {"task": task, "policy": policy, "channel": channel, "success": success, "t_stable": t,
            "lscr": lscr, "cscr": cscr, "drop": drop, "high_speed": high, "hard_violation": drop or high,
            "safe_success": success and not (drop or high), "violation_steps": viol, "n_steps": n,
            "isr_ever": success if isr is None else isr, "success_final": success if final is None else final,
            "termination": "stable_success" if success else "horizon", "te": None, "gsi": None, "gsi_mean": None}


RECORDS = [
    rec("none", True, t=2.0, viol=0, n=100),
    rec("none", True, t=4.0, cscr=0.5, drop=True, viol=10, n=200),
    rec("none", False, lscr=0.5, cscr=0.0, high=True, viol=5, n=300, isr=True),
    rec("none", False, lscr=0.0, cscr=0.0, n=400),
    rec("equi_only", True, t=1.0), rec("equi_only", False, lscr=0.5),
    rec("inv_only", False), rec("inv_only", False),
    rec("inv_equi", True, t=3.0), rec("inv_equi", True, t=5.0),
    rec("none", False, policy="dp"), rec("none", False, policy="dp"), rec("inv_equi", True, t=1.0, policy="dp"),
]


def test_cell_metrics_hand_computed():
    cells = cell_metrics(RECORDS).set_index(["task", "policy", "channel"])
    none = cells.loc[("t1", "act", "none")]
    assert none["N"] == 4 and none["n_success"] == 2 and none["SR"] == 0.5
    assert none["t_succ"] == 3.0 and none["LSCR"] == 0.625 and none["CSCR"] == 0.375
    assert none["SafeSR"] == 0.25 and none["HVR"] == 0.5 and none["DropR"] == 0.25 and none["HSR"] == 0.25
    assert none["VSR_step"] == 15 / 1000  # pooled over steps, not a mean of per-episode rates
    assert none["ISR_ever"] == 0.75 and none["SR_final"] == 0.5
    assert (none["SR_ci_low"], none["SR_ci_high"]) == (0.0, 1.0)  # P(0 of 4) = 1/16 > 2.5 %
    assert math.isnan(none["TE"]) and math.isnan(none["GSI"])
    inv = cells.loc[("t1", "act", "inv_only")]
    assert inv["SR"] == 0.0 and math.isnan(inv["t_succ"]) and inv["t_succ_note"].startswith("undefined")
    assert cells.loc[("t1", "act", "inv_equi"), "t_succ"] == 4.0


def test_channel_robustness_ratios_and_shift():
    rob = channel_robustness(RECORDS).set_index(["task", "policy"])
    act = rob.loc[("t1", "act")]
    assert act["SR_none"] == 0.5 and act["N_none"] == 4
    assert (act["RR_equi_only"], act["RR_inv_only"], act["RR_inv_equi"]) == (1.0, 0.0, 2.0)
    assert act["N_shift"] == 6 and act["SR_shift"] == 0.5 and act["RR_shift"] == 1.0
    dp = rob.loc[("t1", "dp")]
    assert dp["SR_none"] == 0.0 and math.isnan(dp["RR_inv_equi"]) and math.isnan(dp["RR_shift"])
    assert dp["N_equi_only"] == 0 and math.isnan(dp["SR_equi_only"]) and dp["SR_shift"] == 1.0
    assert dp["RR_note"].startswith("undefined")
    # the same from precomputed cells
    again = channel_robustness(cell_metrics(RECORDS)).set_index(["task", "policy"])
    assert again.loc[("t1", "act"), "RR_shift"] == 1.0


def test_unknown_channel_rejected():
    with pytest.raises(ValueError, match="full"):
        channel_robustness([rec("full", True, t=1.0)])


def test_bootstrap_is_deterministic_and_sane():
    x = np.array([1.0] * 25 + [0.0] * 25)
    a, b = bootstrap_ci(x), bootstrap_ci(x)
    assert a == b
    assert a == (0.36, 0.64)  # seed 0, 10,000 resamples; normal approximation 0.5 +- 0.139
    assert bootstrap_ci(np.ones(7)) == (1.0, 1.0)
    graded = np.linspace(0.0, 1.0, 21)  # continuous values: the seed shows
    assert bootstrap_ci(graded) == bootstrap_ci(graded) != bootstrap_ci(graded, seed=1)
    assert all(math.isnan(v) for v in bootstrap_ci([]))


def test_task_macro_is_equal_weight_over_tasks():
    records = [rec("none", True, t=1.0, task="t1"), rec("none", False, task="t1"),
               rec("none", True, t=1.0, task="t2")] + [rec("none", False, task="t2")] * 0
    macro = task_macro(cell_metrics(records))
    assert macro.loc[0, "SR"] == 0.75 and macro.loc[0, "n_tasks"] == 2


def test_accepts_episode_records_and_dataframes():
    s = scene({"apple": resting("apple")})
    records = [evaluate_states({"terminal": {"upright": {"object": "apple"}}}, context(), [s] * n, 0.1,
                               labels={"task": "t", "policy": "p", "channel": "none"})[0] for n in (3, 6)]
    cells = cell_metrics(records)
    assert cells.loc[0, "SR"] == 0.5 and cells.loc[0, "t_succ"] == pytest.approx(0.5)
    assert cell_metrics(pd.DataFrame([r.to_dict() for r in records])).equals(cells)
    with pytest.raises(ValueError, match="success"):
        cell_metrics(pd.DataFrame([{"task": "t", "policy": "p", "channel": "none"}]))
