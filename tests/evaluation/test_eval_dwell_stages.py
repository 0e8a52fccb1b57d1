"""Reach-and-stop dwell and latched stages through EpisodeEvaluator, on exact synthetic sequences."""

import numpy as np
import pytest
from eval_synth import context, obj, resting, scene

from evaluation import EpisodeEvaluator, evaluate_states

DOOR_OPEN = {"joint_open": {"joint": "fridge/door", "threshold": 1.0}}
FRIDGE = obj([0.6, 0.0, 1.35])


def door(*values):
    return [scene({"fridge": FRIDGE, "bottle": obj([0.6, 0, 1.0])}, joints={"fridge/door": v}) for v in values]


def test_dwell_accumulates_resets_and_gives_exact_t_stable():
    states = door(1.2, 1.2, 0.0, 1.2, 1.2, 1.2, 1.2, 1.2)  # C = 1 1 0 1 1 1 1 1
    record, t = evaluate_states({"terminal": DOOR_OPEN, "dwell_s": 0.5}, context(), states, 0.125)
    assert t["dwell_s"].tolist() == [0.125, 0.25, 0.0, 0.125, 0.25, 0.375, 0.5, 0.625]
    assert t["stable"].tolist() == [False] * 6 + [True, True]
    assert record.success and record.steps_to_stable == 7 and record.t_stable == 0.875
    assert record.isr_ever and record.success_final and record.n_steps == 8 and record.duration_s == 1.0
    assert record.termination == "stable_success"


def test_dwell_of_thirty_physics_steps_at_60_hz_is_reached():
    # 30 x (1/60) sums to 0.49999999999999994: the tolerance keeps the paper's h >= 0.5 at j = 30
    record, _ = evaluate_states({"terminal": DOOR_OPEN}, context(), door(*[1.2] * 31), 1 / 60)
    assert record.steps_to_stable == 30 and record.t_stable == pytest.approx(0.5, abs=1e-12)


def test_transient_terminal_is_not_success():
    record, t = evaluate_states({"terminal": DOOR_OPEN}, context(), door(1.2, 1.2, 1.2, 0.0), 0.125)
    assert not record.success and record.t_stable is None and record.steps_to_stable is None
    assert record.isr_ever and not record.success_final and record.termination == "horizon"
    assert t["terminal"].tolist() == [True, True, True, False]


def test_stop_at_stable_and_expert_efficiency():
    spec = {"terminal": DOOR_OPEN, "expert_horizon_steps": 8}
    record, t = evaluate_states(spec, context(), door(*[1.2] * 10), 0.125, stop_at_stable=True)
    assert record.n_steps == 4 and len(t["terminal"]) == 4
    assert record.t_expert == 1.0 and record.te == 2.0  # t_expert = 8 x 0.125 s; t_stable = 0.5 s
    record, _ = evaluate_states({**spec, "sim_dt_s": 0.0625}, context(), door(*[1.2] * 4), 0.125)
    assert record.te == 1.0


FRIDGE_STAGES = [
    {"id": "door_closed", "predicate": {"joint_closed": {"joint": "fridge/door", "threshold": 0.1}},
     "depends_on": ["bottle_out"]},
    {"id": "door_open", "predicate": DOOR_OPEN},
    {"id": "bottle_out", "depends_on": ["door_open"],
     "predicate": {"all": [{"lifted": {"object": "bottle", "min_height": 0.05}},
                           {"not": {"inside": {"object": "bottle", "container": "fridge"}}}]}},
]
FRIDGE_SPEC = {"terminal": {"all": [{"latched": "bottle_out"}, {"stage": "door_closed"}]}, "stages": FRIDGE_STAGES}


def fridge_states(frames):
    """frames: (door angle, bottle position)."""
    return [scene({"fridge": FRIDGE, "bottle": obj(p)}, joints={"fridge/door": d}) for d, p in frames]


IN, OUT = [0.6, 0, 1.0], [0.2, 0, 1.1]


def test_latched_stage_keeps_progress_after_the_door_is_closed_again():
    states = fridge_states([(0.0, IN), (1.2, IN), (1.2, OUT), (0.0, OUT)] + [(0.0, OUT)] * 4)
    ev = EpisodeEvaluator(FRIDGE_SPEC, context())
    for s in states:
        ev.update(s, 0.125)
    r, t = ev.result(), ev.traces()
    assert r.stage_ids == ["door_closed", "door_open", "bottle_out"] == ev.stage_ids
    # door_closed holds at the start, but its dependency is not latched: no latch, not valid
    assert t["stage_value"][0].tolist() == [True, False, False]
    assert t["stage_latched"][0].tolist() == [False, False, False]
    assert t["stage_latched"][:4].tolist() == [[False, False, False], [False, True, False],
                                               [False, True, True], [True, True, True]]
    assert r.stage_latched == [True, True, True] and r.lscr == 1.0
    assert r.stage_latched_at_s == [0.5, 0.25, 0.375]
    assert r.stage_final == [True, False, True]  # the door is no longer open ...
    assert r.stage_final_valid == [True, False, True] and r.cscr == pytest.approx(2 / 3)
    assert r.latched_depth == 3 and r.current_depth == 3 and r.max_depth == 3
    assert t["latched_depth"].tolist()[:4] == [0, 1, 2, 3]
    assert r.success and r.steps_to_stable == 7  # terminal from update 4, dwell 0.5 s at 0.125 s


SAME_STEP = {
    "terminal": {"stage": "c"},
    "stages": [
        {"id": "c", "predicate": {"at_rest": {"objects": ["apple"]}}, "depends_on": ["b"]},
        {"id": "b", "predicate": {"within_distance": {"object": "apple", "target": "seat_a", "max_dist": 0.05}},
         "depends_on": ["a"]},
        {"id": "a", "predicate": {"lifted": {"object": "apple", "min_height": 0.05}}},
    ],
}


def test_same_step_fixed_point_closure_latches_a_whole_chain():
    start = scene({"apple": resting("apple", -0.3, 0.0)})
    there = scene({"apple": obj([0.3, 0.2, 0.85])})
    _, t = evaluate_states(SAME_STEP, context(), [start, there], 0.1)
    assert t["stage_latched"].tolist() == [[False, False, False], [True, True, True]]
    assert t["latched_depth"].tolist() == [0, 3] and t["current_depth"].tolist() == [0, 3]


def test_stage_true_before_its_dependency_waits_for_it():
    spec = {"terminal": DOOR_OPEN, "stages": [
        {"id": "open", "predicate": DOOR_OPEN},
        {"id": "up", "predicate": {"upright": {"object": "bottle"}}, "depends_on": ["open"]}]}
    _, t = evaluate_states(spec, context(), door(0.0, 0.0, 1.2), 0.1)
    assert t["stage_value"][:, 1].tolist() == [True, True, True]
    assert t["stage_latched"][:, 1].tolist() == [False, False, True]  # latched with its dependency


def test_stage_that_held_only_before_its_dependency_never_latches():
    spec = {"terminal": DOOR_OPEN, "stages": [
        {"id": "open", "predicate": DOOR_OPEN},
        {"id": "out", "predicate": {"lifted": {"object": "bottle", "min_height": 0.05}}, "depends_on": ["open"]}]}
    frames = [(0.0, IN), (0.0, [0.6, 0, 1.2]), (1.2, IN), (1.2, IN)]
    record, t = evaluate_states(spec, context(), fridge_states(frames), 0.1)
    assert t["stage_value"][:, 1].tolist() == [False, True, False, False]
    assert record.stage_latched == [True, False] and record.lscr == 0.5
    record, _ = evaluate_states(spec, context(), fridge_states(frames + [(1.2, [0.6, 0, 1.2])]), 0.1)
    assert record.stage_latched == [True, True]


def test_reset_reuses_the_compiled_spec_deterministically():
    states = fridge_states([(0.0, IN), (1.2, IN), (1.2, OUT), (0.0, OUT), (0.0, OUT)])
    ev = EpisodeEvaluator(FRIDGE_SPEC, context(), labels={"task": "fridge"})
    runs = []
    for _ in range(2):
        ev.reset()
        for s in states:
            ev.update(s, 0.125)
        runs.append((ev.result().to_dict(), ev.traces()))
    assert runs[0][0] == runs[1][0]
    for k in runs[0][1]:     # NaN (motion traces without robot state) counts as equal to NaN
        np.testing.assert_array_equal(runs[0][1][k], runs[1][1][k], err_msg=k)


def test_bad_dt_is_rejected():
    ev = EpisodeEvaluator({"terminal": DOOR_OPEN}, context())
    with pytest.raises(ValueError, match="dt"):
        ev.update(door(0.0)[0], 0.0)


def test_presses_before_a_stage_s_dependencies_hold_do_not_count():
    """gaming_desk_setup's click depends on the mouse being moved: a press while it is still carried
    (here: before the door opens) is forgotten; the press after it counts."""
    click = {"key_pressed_sequence": {"keys": ["piano/C4"], "press_threshold": 0.02}}
    spec = {"terminal": DOOR_OPEN, "stages": [
        {"id": "open", "predicate": DOOR_OPEN},
        {"id": "click", "predicate": {"all": [click]}, "depends_on": ["open"]}]}
    frames = [(0.0, 0.0), (0.0, 0.03), (0.0, 0.0), (1.2, 0.0), (1.2, 0.0), (1.2, 0.03), (1.2, 0.0)]
    states = [scene({"fridge": FRIDGE, "piano": resting("piano")}, joints={"fridge/door": d, "piano/C4": c})
              for d, c in frames]
    _, t = evaluate_states(spec, context(), states, 0.1)
    assert t["stage_latched"][:, 0].tolist() == [False, False, False, True, True, True, True]
    assert t["stage_latched"][:, 1].tolist() == [False] * 6 + [True]


def test_a_key_held_down_while_a_stage_s_dependencies_latch_counts_only_when_pressed_again():
    click = {"key_pressed_sequence": {"keys": ["piano/C4"], "press_threshold": 0.02}}
    spec = {"terminal": DOOR_OPEN, "stages": [
        {"id": "open", "predicate": DOOR_OPEN},
        {"id": "click", "predicate": click, "depends_on": ["open"]}]}
    # pressed while shut, held as the door opens, released; then pressed and released again
    frames = [(0.0, 0.03), (1.2, 0.03), (1.2, 0.03), (1.2, 0.0), (1.2, 0.03), (1.2, 0.0)]
    states = [scene({"fridge": FRIDGE, "piano": resting("piano")}, joints={"fridge/door": d, "piano/C4": c})
              for d, c in frames]
    _, t = evaluate_states(spec, context(), states, 0.1)
    assert t["stage_latched"][:, 1].tolist() == [False] * 5 + [True]
