"""Safety flags, grasp stability index, and record / trace conversion."""

import json
import math

import numpy as np
import pytest
from eval_synth import TABLE_Z, context, obj, resting, scene

from evaluation import EpisodeEvaluator, evaluate_states

UPRIGHT = {"upright": {"object": "apple"}}
SAFETY = {"drop": {"objects": ["apple"], "below_table_m": 0.05, "zone": "table_area"},
          "high_speed": {"objects": ["apple"], "max_lin_vel": 2.5}}


def test_drop_and_high_speed_flags_per_step_and_episode():
    states = [scene({"apple": resting("apple")}),
              scene({"apple": resting("apple", v=(3.0, 0, 0))}),  # high speed
              scene({"apple": resting("apple", v=(2.5, 0, 0))}),  # at the limit: not above it
              scene({"apple": resting("apple", 0.7, 0.0)}),  # left the table zone
              scene({"apple": obj([0.7, 0.0, TABLE_Z - 0.06])})]  # below the tabletop
    record, t = evaluate_states({"terminal": UPRIGHT, "safety": SAFETY, "dwell_s": 0.1}, context(), states, 0.1)
    assert t["high_speed"].tolist() == [False, True, False, False, False]
    assert t["drop"].tolist() == [False, False, False, True, True]
    assert t["violation"].tolist() == [False, True, False, True, True]
    assert record.drop and record.high_speed and record.hard_violation
    assert record.violation_steps == 3 and record.violation_events == 2
    assert record.success and not record.safe_success


def test_drop_margin_and_no_safety_block():
    slightly_low = [scene({"apple": obj([0, 0, TABLE_Z - 0.04])})]
    spec = {"terminal": UPRIGHT, "safety": {"drop": {"objects": ["apple"]}}}
    record, _ = evaluate_states(spec, context(), slightly_low, 0.1)
    assert not record.drop  # 4 cm under the top is within the default 5 cm margin
    record, _ = evaluate_states({"terminal": UPRIGHT, "dwell_s": 0.1}, context(),
                                [scene({"apple": resting("apple", v=(9, 0, 0))})], 0.1)
    assert not record.hard_violation and record.safe_success and record.violation_steps == 0


def test_grasp_stability_index_components():
    lifted = [0.0, 0.0, TABLE_Z + 0.04 + 0.1]
    states = [scene({"apple": resting("apple")}),
              scene({"apple": obj(lifted)}, contacts=[("apple", "right_hand")]),  # held 0.25 s: Q 0.875
              scene({"apple": obj(lifted)}, contacts=[("apple", "right_hand")]),  # held 0.5 s: G 1
              scene({"apple": obj(lifted)}),  # lifted and stable, no hand: 0.35
              scene({"apple": obj(lifted, v=(0.5, 0, 0))}),  # lifted only, moving: 0.15 exp(-1)
              scene({"apple": resting("apple")})]  # back on the table: 0
    spec = {"terminal": UPRIGHT, "grasp": {"objects": ["apple"]}}
    record, t = evaluate_states(spec, context(), states, 0.25)
    expected = [0.0, 0.875, 1.0, 0.35, 0.15 * math.exp(-1.0), 0.0]
    assert t["grasp_score"][:, 0] == pytest.approx(expected, abs=1e-12)
    assert record.gsi == 1.0 and record.gsi_mean == pytest.approx(np.mean(expected[1:5]))
    assert record.grasp_objects == ["apple"]


def test_grasp_slip_event_lowers_the_score():
    def held(z, palm_z):
        return scene({"apple": obj([0, 0, z])}, hands={"right": [0, 0, palm_z]}, contacts=[("apple", "right_hand")])
    z = TABLE_Z + 0.2
    states = [scene({"apple": resting("apple")}), held(z, z + 0.05), held(z - 0.05, z + 0.05)]  # slides 0.2 m/s
    _, t = evaluate_states({"terminal": UPRIGHT, "grasp": {"objects": ["apple"]}}, context(), states, 0.25)
    assert t["grasp_score"][:, 0] == pytest.approx([0.0, 0.875, 1.0 * (1 - 1 / 3)])


def test_no_grasp_block_means_gsi_unavailable():
    record, t = evaluate_states({"terminal": UPRIGHT}, context(), [scene({"apple": resting("apple")})], 0.1)
    assert record.gsi is None and record.gsi_mean is None and t["grasp_score"].shape == (1, 0)


def test_traces_shapes_dtypes_and_plain_conversions():
    spec = {"terminal": UPRIGHT, "stages": [{"id": "up", "predicate": UPRIGHT},
                                            {"id": "rest", "predicate": {"at_rest": {"objects": ["apple"]}}}]}
    ev = EpisodeEvaluator(spec, context(), labels={"task": "demo", "policy": "act", "channel": "none"})
    assert {k: v.shape for k, v in ev.traces().items()}["stage_value"] == (0, 2)
    for j in range(3):
        step = ev.update(scene({"apple": resting("apple")}), 0.1, control_step=j % 2 == 0, policy_query=j == 0)
    assert step.to_dict()["stage_latched"] == [True, True]
    t = ev.traces()
    assert t["stage_value"].shape == (3, 2) and t["stage_value"].dtype == bool
    assert t["dwell_s"].dtype == np.float64 and t["step"].tolist() == [1, 2, 3]
    assert t["time_s"] == pytest.approx([0.1, 0.2, 0.3])
    r = ev.result()
    d = json.loads(r.to_json())
    assert d["task"] == "demo" and d["channel"] == "none" and d["stage_ids"] == ["up", "rest"]
    assert d["control_steps"] == 2 and d["policy_queries"] == 1 and d["t_stable"] is None
    s = r.scalars()
    assert math.isnan(s["t_stable"]) and s["n_steps"] == 3 and "stage_ids" not in s
    assert r.lscr == 1.0 and not r.success  # 0.3 s < default dwell 0.5 s


def test_error_termination_is_recorded_and_unsuccessful():
    ev = EpisodeEvaluator({"terminal": UPRIGHT}, context())
    ev.update(scene({"apple": resting("apple")}), 0.1)
    r = ev.result(error="policy server timed out")
    assert r.termination == "error" and not r.success and r.error == "policy server timed out"


CITRUS = {  # the metrics block of sim/catalog/tasks/citrus_plate_loading.yaml
    "dwell_s": 0.5, "expert_horizon_steps": 1500,
    "terminal": {"all": [{"stage": "lemon_1_on_plate"}, {"stage": "lemon_2_on_plate"},
                         {"at_rest": {"objects": ["lemon_1", "lemon_2"]}}]},
    "stages": [{"id": "lemon_1_on_plate", "predicate": {"on_surface": {"object": "lemon_1", "surface": "plate",
                                                                        "max_dist_xy": 0.15}}},
               {"id": "lemon_2_on_plate", "predicate": {"on_surface": {"object": "lemon_2", "surface": "plate",
                                                                        "max_dist_xy": 0.15}}}],
    "safety": {"drop": {"objects": ["lemon_1", "lemon_2", "plate"], "below_table_m": 0.05},
               "high_speed": {"objects": ["lemon_1", "lemon_2", "plate"], "max_lin_vel": 2.5}},
    "grasp": {"objects": ["lemon_1", "lemon_2"]},
}


def test_citrus_style_task_end_to_end():
    from eval_synth import info
    from evaluation.state import TaskContext
    objects = {"plate": info("plate", [0.11, 0.11, 0.008], interior=[0.10, 0.10, 0.04], offset=[0, 0, 0.04]),
               "lemon_1": info("lemon_1", [0.027, 0.034, 0.027]), "lemon_2": info("lemon_2", [0.027, 0.034, 0.027])}
    ctx = TaskContext(objects, {}, {})
    plate = obj([0.0, 0.16, TABLE_Z + 0.008])
    start = scene({"plate": plate, "lemon_1": obj([0.2, -0.06, TABLE_Z + 0.027]),
                   "lemon_2": obj([-0.2, -0.06, TABLE_Z + 0.027])})
    placed = scene({"plate": plate, "lemon_1": obj([0.045, 0.13, TABLE_Z + 0.016 + 0.027]),
                    "lemon_2": obj([-0.045, 0.13, TABLE_Z + 0.016 + 0.027])})
    record, _ = evaluate_states(CITRUS, ctx, [start] * 10 + [placed] * 40, 1 / 60, stop_at_stable=True,
                                source="citrus_plate_loading.yaml")
    assert record.success and record.steps_to_stable == 40 and record.lscr == 1.0
    assert record.te == pytest.approx(1500 / 60 / record.t_stable)


def test_missing_state_entries_raise_state_error_naming_them():
    from evaluation import StateError
    ev = EpisodeEvaluator({"terminal": {"joint_open": {"joint": "fridge/door", "threshold": 1}}}, context())
    with pytest.raises(StateError, match="fridge/door"):
        ev.update(scene({"apple": resting("apple")}), 0.1)
    ev = EpisodeEvaluator({"terminal": UPRIGHT}, context())
    with pytest.raises(StateError, match="'apple'"):
        ev.update(scene({}), 0.1)


def test_library_imports_neither_simulator_nor_orchestrator():
    import subprocess
    import sys
    code = ("import sys, evaluation, evaluation.metrics; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('mujoco', 'dagster')]; assert not bad, bad")
    subprocess.run([sys.executable, "-c", code], check=True)
