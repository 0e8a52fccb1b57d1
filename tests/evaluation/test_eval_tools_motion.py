"""Tool selection accuracy, tool switch success and robot-motion RMS on exact synthetic sequences."""

import math

import numpy as np
import pytest
from eval_synth import TABLE_Z, context, obj, resting, scene

from evaluation import EpisodeEvaluator, SceneState, TaskSpecError, evaluate_states
from evaluation.metrics import cell_metrics

DT = 0.1
HOME = {"hammer": (0.3, 0.0), "bottle": (-0.3, 0.0), "glass_1": (0.0, 0.3), "block": (0.0, -0.3)}
BLOCK_SERVED = {"in_zone": {"object": "block", "zone": "serve"}}     # serve: centre (0.4, -0.2)
APPLE_CENTRED = {"in_zone": {"object": "apple", "zone": "center"}}


def frame(held=(), touched=(), block_served=False, apple_centred=False, at=None, moving=()) -> SceneState:
    """Objects at home on the table; ``held``: lifted 0.1 m and touching the right hand; ``touched``:
    on the table, touching the right hand; ``at``: {name: xyz} overrides; ``moving``: 1 m/s."""
    objects = {n: resting(n, *xy, v=(1.0, 0, 0) if n in moving else (0, 0, 0)) for n, xy in HOME.items()}
    objects["apple"] = resting("apple", 0.0 if apple_centred else -0.4, 0.0)
    if block_served:
        objects["block"] = resting("block", 0.4, -0.2)
    for n in held:
        p = objects[n].pos
        objects[n] = obj([p[0], p[1], p[2] + 0.1], v=(1.0, 0, 0) if n in moving else (0, 0, 0))
    for n, xyz in (at or {}).items():
        objects[n] = obj(xyz)
    contacts = [(n, "right_hand") for n in (*held, *touched)]
    return scene(objects, contacts=contacts)


def spec(stages, **extra):
    return {"terminal": BLOCK_SERVED, "stages": stages, "safety": {"drop": {"objects": ["hammer", "bottle"]}},
            **extra}


ONE_STAGE = spec([{"id": "strike", "predicate": BLOCK_SERVED, "tools": ["hammer"]}])
# strike with the hammer, then pour with a pourer; the hammer is carried into the pour stage
TWO_STAGES = spec([{"id": "strike", "predicate": BLOCK_SERVED, "tools": ["hammer"]},
                   {"id": "pour", "predicate": APPLE_CENTRED, "depends_on": ["strike"],
                    "tools": [{"class": "pourer"}]}],
                  tool_use={"classes": {"pourer": ["bottle", "glass_1"]}, "switch_timeout_s": 2.0})


def evaluate(metrics, frames):
    return evaluate_states(metrics, context(), frames, DT)


# -- TSA ---------------------------------------------------------------------------------------------
def test_correct_tool_is_selected():
    record, traces = evaluate(ONE_STAGE, [frame(), frame(held=["hammer"]), frame(held=["hammer"], block_served=True)])
    assert record.tsa == 1.0 and record.tool_selected == ["hammer"] and record.tool_correct == [True]
    assert record.tool_candidates == ["hammer"] and traces["tool_held"][:, 0].tolist() == [False, True, True]


def test_first_held_wrong_object_makes_the_stage_incorrect():
    frames = [frame(), frame(held=["bottle"]), frame(held=["hammer"]), frame(held=["hammer"], block_served=True)]
    record, _ = evaluate(ONE_STAGE, frames)
    assert record.tsa == 0.0 and record.tool_selected == ["bottle"] and record.tool_correct == [False]


def test_stage_without_a_selected_tool_is_incorrect():
    record, _ = evaluate(ONE_STAGE, [frame(), frame(block_served=True), frame(block_served=True)])
    assert record.stage_latched == [True]
    assert record.tsa == 0.0 and record.tool_selected == [None] and record.tool_correct == [False]


def test_tool_class_and_carried_tool():
    """The hammer still held when the pour stage opens is no selection; a pourer picked next is."""
    frames = [frame(), frame(held=["hammer"]), frame(held=["hammer"], block_served=True),
              frame(held=["hammer"], block_served=True), frame(block_served=True),
              frame(held=["glass_1"], block_served=True), frame(held=["glass_1"], block_served=True, apple_centred=True)]
    record, _ = evaluate(TWO_STAGES, frames)
    assert record.tool_stage_ids == ["strike", "pour"]
    assert record.tool_selected == ["hammer", "glass_1"] and record.tsa == 1.0
    assert record.tool_candidates == ["hammer", "bottle", "glass_1"]
    # re-grasping the hammer during the pour stage is a (wrong) selection
    frames.insert(5, frame(held=["hammer"], block_served=True))
    record, _ = evaluate(TWO_STAGES, frames)
    assert record.tool_selected == ["hammer", "hammer"] and record.tool_correct == [True, False]
    assert record.tsa == 0.5


def test_tool_use_undefined_without_tool_annotations():
    metrics = spec([{"id": "strike", "predicate": BLOCK_SERVED}])
    record, traces = evaluate(metrics, [frame(held=["hammer"]), frame(), frame(touched=["bottle"])])
    assert record.tsa is None and record.tssr is None and record.tool_switch_attempts == 0
    assert record.tool_stage_ids == [] and traces["tool_held"].shape == (3, 0)
    assert math.isnan(record.scalars()["tsa"]) and '"tsa": null' in record.to_json()


# -- TSSR --------------------------------------------------------------------------------------------
def switch_frames(first_tool_after_release, grasp_from, n=12):
    """Hold the hammer, release it (to ``first_tool_after_release``), touch the bottle, then hold the
    bottle from frame ``grasp_from`` on (frame 2 is the release; frame 0 the initial state)."""
    frames = [frame(), frame(held=["hammer"])]
    for i in range(2, n):
        if i >= grasp_from:
            frames.append(frame(held=["bottle"], at=first_tool_after_release))
        else:
            frames.append(frame(touched=["bottle"] if i >= 3 else [], at=first_tool_after_release))
    return frames


def test_successful_switch():
    record, _ = evaluate(TWO_STAGES, switch_frames({}, grasp_from=4))
    assert record.tool_switch_attempts == 1 and record.tool_switch_successes == 1 and record.tssr == 1.0


def test_switch_that_drops_the_first_tool_fails():
    dropped = {"hammer": [0.3, 0.0, TABLE_Z - 0.3]}      # fell off the table
    record, _ = evaluate(TWO_STAGES, switch_frames(dropped, grasp_from=4))
    assert record.tool_switch_attempts == 1 and record.tool_switch_successes == 0 and record.tssr == 0.0


def test_switch_that_times_out_fails():
    # timeout 2.0 s: the release is at t=0.3 s; a grasp from frame 25 has lasted 0.5 s at t=3.0 s
    record, _ = evaluate(TWO_STAGES, switch_frames({}, grasp_from=25, n=40))
    assert record.tool_switch_attempts == 1 and record.tool_switch_successes == 0 and record.tssr == 0.0
    # the same grasp inside the window succeeds
    record, _ = evaluate(TWO_STAGES, switch_frames({}, grasp_from=15, n=40))
    assert record.tssr == 1.0


def test_first_tool_must_come_to_rest():
    frames = switch_frames({}, grasp_from=4)
    moving = [frame(held=["bottle"] if i >= 4 else [], touched=["bottle"] if i == 3 else [], moving=["hammer"])
              for i in range(2, 12)]
    record, _ = evaluate(TWO_STAGES, frames[:2] + moving)
    assert record.tool_switch_attempts == 1 and record.tssr == 0.0      # the hammer never settled
    assert evaluate(TWO_STAGES, frames)[0].tssr == 1.0


def test_tssr_undefined_without_an_attempt():
    # the hammer is put down and nothing else is touched: a release, not a switch
    record, _ = evaluate(TWO_STAGES, [frame(), frame(held=["hammer"])] + [frame()] * 40)
    assert record.tssr is None and record.tool_switch_attempts == 0
    # re-grasping the same tool is no switch either
    frames = [frame(), frame(held=["hammer"]), frame(), frame(held=["hammer"]),
              frame(touched=["bottle"], held=["hammer"])]
    record, _ = evaluate(TWO_STAGES, frames)
    assert record.tssr is None


# -- spec errors ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("tools, field, words", [
    (["crowbar"], "metrics.stages[0].tools[0]", ["crowbar", "hammer"]),
    ([{"class": "levers"}], "metrics.stages[0].tools[0].class", ["levers", "pourer"]),
    ([], "metrics.stages[0].tools", ["non-empty list"]),
    ([{"kind": "pourer"}], "metrics.stages[0].tools[0]", ["{class: name}"]),
])
def test_bad_tools_fail_at_load_naming_file_and_field(tools, field, words):
    metrics = spec([{"id": "strike", "predicate": BLOCK_SERVED, "tools": tools}],
                   tool_use={"classes": {"pourer": ["bottle"]}})
    with pytest.raises(TaskSpecError) as info:
        EpisodeEvaluator(metrics, context(), source="tasks/x.yaml")
    assert info.value.field == field and str(info.value).startswith(f"tasks/x.yaml: {field}")
    assert all(w in str(info.value) for w in words)


@pytest.mark.parametrize("tool_use, field", [
    ({"classes": {"pourer": ["bottle", "jug"]}}, "metrics.tool_use.classes.pourer[1]"),
    ({"switch_timeout_s": 0}, "metrics.tool_use.switch_timeout_s"),
    ({"timeout": 3}, "metrics.tool_use.timeout"),
])
def test_bad_tool_use_block(tool_use, field):
    with pytest.raises(TaskSpecError) as info:
        EpisodeEvaluator(spec([], tool_use=tool_use), context(), source="tasks/x.yaml")
    assert info.value.field == field


# -- robot motion --------------------------------------------------------------------------------------
def robot_frames(qvels, efforts):
    base = frame()
    return [SceneState(base.time_s, base.objects, base.joints, base.hands, base.table_height, base.contacts,
                       robot_qvel=None if v is None else np.array(v, float),
                       robot_effort=None if e is None else np.array(e, float)) for v, e in zip(qvels, efforts)]


def test_motion_rms_against_hand_computed_values():
    qvel = [[0, 0], [1, 0], [1, 2], [0, 2]]           # dt 0.5: acc [2,0] [0,4] [-2,0]; jerk [-4,8] [-4,-8]
    effort = [[3, -4]] * 4
    record, t = evaluate_states(ONE_STAGE, context(), robot_frames(qvel, effort), 0.5)
    assert record.joint_vel_rms == pytest.approx(math.sqrt(10 / 8))
    assert record.joint_acc_rms == pytest.approx(math.sqrt(24 / 6))
    assert record.joint_jerk_rms == pytest.approx(math.sqrt(160 / 4))
    assert record.joint_effort_rms == pytest.approx(math.sqrt(12.5))
    np.testing.assert_allclose(t["joint_vel_rms"], [0, math.sqrt(0.5), math.sqrt(2.5), math.sqrt(2)])
    np.testing.assert_allclose(t["joint_acc_rms"], [np.nan, math.sqrt(2), math.sqrt(8), math.sqrt(2)])
    np.testing.assert_allclose(t["joint_jerk_rms"], [np.nan, np.nan, math.sqrt(40), math.sqrt(40)])


def test_motion_undefined_without_robot_state_and_gap_restarts_differences():
    record, t = evaluate(ONE_STAGE, [frame(), frame()])
    assert record.joint_vel_rms is None and record.joint_jerk_rms is None and np.isnan(t["joint_vel_rms"]).all()
    record, _ = evaluate_states(ONE_STAGE, context(), robot_frames([[0.0], None, [1.0], [3.0]], [None] * 4), 1.0)
    assert record.joint_acc_rms == pytest.approx(2.0) and record.joint_jerk_rms is None
    assert record.joint_effort_rms is None


# -- aggregation ---------------------------------------------------------------------------------------
def test_cell_means_over_defined_episodes_with_switch_counts():
    def rec(tsa, tssr, attempts, successes, vel):
        return {"task": "t", "policy": "p", "channel": "none", "success": True, "t_stable": 1.0, "lscr": 1.0,
                "cscr": 1.0, "drop": False, "high_speed": False, "hard_violation": False, "safe_success": True,
                "violation_steps": 0, "n_steps": 10, "isr_ever": True, "success_final": True, "tsa": tsa,
                "tssr": tssr, "tool_switch_attempts": attempts, "tool_switch_successes": successes,
                "joint_vel_rms": vel}
    records = [rec(1.0, None, 0, 0, 0.2), rec(None, 1.0, 2, 2, None), rec(0.5, 0.0, 1, 0, 0.4)]
    cell = cell_metrics(records, n_boot=10).iloc[0]
    assert cell["TSA"] == 0.75 and cell["n_TSA"] == 2
    assert cell["TSSR"] == 0.5 and cell["n_TSSR"] == 2
    assert cell["switch_attempts"] == 3 and cell["switch_successes"] == 2
    assert cell["JointVel_RMS"] == pytest.approx(0.3) and np.isnan(cell["JointJerk_RMS"])
