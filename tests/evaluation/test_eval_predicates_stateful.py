"""Stateful predicates: key_pressed_sequence, struck_once, sequence (and their reset)."""

from eval_synth import context, obj, resting, run, scene

from evaluation.predicates import compile_condition

KEYS = {"key_pressed_sequence": {"keys": ["piano/C4", "piano/C4", "piano/G4"], "press_threshold": 0.02}}


def keys(*frames):
    return [scene({"piano": resting("piano")}, joints={"piano/C4": c, "piano/G4": g}) for c, g in frames]


FRAMES = keys((0, 0), (0.03, 0), (0, 0), (0, 0.03), (0, 0), (0.03, 0), (0.015, 0), (0, 0), (0, 0.03), (0, 0),
              (0.03, 0.03))


def test_key_sequence_in_order_with_hysteresis_and_ignored_wrong_key():
    cond = compile_condition(KEYS, context())
    # C down/up, stray G ignored, C down (0.015 is still down: release at 0.01), C up, G down, G up -> done
    assert run(cond, FRAMES) == [False] * 9 + [True, True]


def test_key_sequence_strict_restarts_on_wrong_key():
    cond = compile_condition({"key_pressed_sequence": {**KEYS["key_pressed_sequence"], "strict": True}}, context())
    assert not any(run(cond, FRAMES))
    clean = keys((0.03, 0), (0, 0), (0.03, 0), (0, 0), (0, 0.03), (0, 0))
    cond.reset()
    assert run(cond, clean) == [False] * 5 + [True]


def test_key_sequence_negative_direction_and_reset():
    spec = {"key_pressed_sequence": {"keys": ["piano/C4"], "press_threshold": -0.02, "direction": "negative"}}
    cond = compile_condition(spec, context())
    frames = keys((0, 0), (-0.03, 0), (-0.005, 0))
    assert run(cond, frames) == [False, False, True]
    cond.reset()
    assert run(cond, frames[:2]) == [False, False]


def strike_frames(heads, speeds=None, contacts=None, block_v=None, ang=None):
    """Hammer (head 0.15 m along its +x) moving toward a block centred at (0, 0, 0.8)."""
    n = len(heads)
    speeds, contacts = speeds or [0.0] * n, contacts or [False] * n
    block_v, ang = block_v or [0.0] * n, ang or [0.0] * n
    out = []
    for hx, v, c, bv, w in zip(heads, speeds, contacts, block_v, ang):
        hammer = obj([hx - 0.15, 0.0, 0.8], v=(v, 0, 0), w=(0, 0, w))
        block = obj([0.0, 0.0, 0.8], v=(bv, 0, 0))
        out.append(scene({"hammer": hammer, "block": block}, contacts=[("block", "hammer")] if c else []))
    return out


STRIKE = {"struck_once": {"tool": "hammer", "target": "block", "min_speed": 1.0, "radius": 0.02,
                          "head_offset": [0.15, 0, 0]}}


def test_struck_once_counts_fast_visits_with_response_exactly_once():
    cond = compile_condition(STRIKE, context())
    frames = strike_frames(
        heads=[-0.3, -0.1, -0.055, -0.1, -0.06, -0.2, -0.1, -0.05, -0.2],
        speeds=[0, 2.0, 2.0, -0.5, 0.1, 0, 2.0, 2.0, 0],
        contacts=[False, False, True, False, True, False, False, False, False],
        block_v=[0, 0, 0, 0, 0, 0, 0, 0.3, 0])
    # strike at frame 2 (fast + contact); slow touch at 4 is no strike; second strike at 7 (block responds)
    assert run(cond, frames) == [False, False, True, True, True, True, True, False, False]


def test_struck_once_needs_a_response_unless_disabled():
    frames = strike_frames(heads=[-0.1, -0.055, -0.2], speeds=[2.0, 2.0, 0.0])
    assert not any(run(compile_condition(STRIKE, context()), frames))
    loose = {"struck_once": {**STRIKE["struck_once"], "require_response": False}}
    assert run(compile_condition(loose, context()), frames) == [False, True, True]


def test_struck_once_head_speed_includes_swing_rotation():
    # no linear velocity, 10 rad/s about z: head speed 10 * 0.15 = 1.5 m/s
    frames = strike_frames(heads=[-0.1, -0.055], ang=[10.0, 10.0], contacts=[False, True])
    assert run(compile_condition(STRIKE, context()), frames) == [False, True]


def ladle(*where):
    spots = {"in": [0.0, 0.0, 0.82], "over": [0.5, 0.0, 0.9], "mid": [0.25, 0.0, 1.0]}
    return [scene({"apple": obj(spots[w]), "box": resting("box"), "plate": resting("plate", 0.5)}) for w in where]


DIP = {"inside": {"object": "apple", "container": "box"}}
POUR = {"within_distance": {"object": "apple", "target": "plate", "max_dist": 0.05, "axes": "xy"}}


def test_sequence_two_rounds_in_order_counting_entries():
    cond = compile_condition({"sequence": {"steps": [DIP, POUR], "times": 2}}, context())
    # starting in the pot is no dip; dip, pour, dip, pour (straight from dip to pour also counts)
    frames = ladle("in", "mid", "in", "in", "over", "mid", "in", "over", "mid")
    assert run(cond, frames) == [False] * 7 + [True, True]
    cond.reset()
    assert run(cond, ladle("over", "in", "over")) == [False, False, False]  # one round only


def test_sequence_single_step_needs_reentry_unless_edge_false():
    frames = ladle("in", "in", "mid", "in", "in", "mid", "in")
    cond = compile_condition({"sequence": {"steps": [DIP], "times": 2}}, context())
    assert run(cond, frames) == [False] * 6 + [True]
    eager = compile_condition({"sequence": {"steps": [DIP], "times": 2, "edge": False}}, context())
    assert run(eager, frames) == [False, True, True, True, True, True, True]
