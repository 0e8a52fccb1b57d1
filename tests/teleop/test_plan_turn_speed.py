"""Plan step `turn`, field `speed` (opt-in): how fast the hand's contact moves along the arc. The check
refuses what is not a speed in (0, 0.3] m/s; without the field the keyframes are what they were (0.09
m/s); twice the speed halves the arc's keyframe durations and moves nothing else."""

import numpy as np
import pytest
import yaml

from sim.errors import SpecError
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample
from sim.tasks import load_task, parse_task
from teleop.recorder import home
from teleop.scripted_operator import ScriptedOperator

TASK, EMBODIMENT, LID = "trash_disposal", "ur5_rh56dfx", "trash_can/lid"
STEP = {"hand": "right", "turn": LID, "to": 1.6}


def _task(tmp_path, **fields):
    raw = yaml.safe_load(load_task(TASK).source.read_text())
    raw["demo_plan"] = [{**STEP, **fields}]
    return parse_task(raw, tmp_path / "bin.yaml")


def _frames(tmp_path, **fields):
    task = _task(tmp_path, **fields)
    scene = build_scene(task, EMBODIMENT, demonstration_sample(task, 0))
    op = ScriptedOperator()
    op.reset(scene, home(scene))
    frames = op.sides["right"]["timeline"].frames
    durations = np.diff([0] + [f.end_step for f in frames])
    return frames, durations


@pytest.mark.parametrize("speed", [0, -0.1, 0.5, "fast", True, None])
def test_speed_must_be_metres_per_second_in_range(tmp_path, speed):
    with pytest.raises(SpecError, match=r"bin.yaml: field 'demo_plan\[0\].speed'.*m/s of the contact along the arc "
                                        r"in \(0, 0.3\]"):
        _task(tmp_path, speed=speed)


def test_default_is_the_former_speed_and_double_halves_the_arc(tmp_path):
    plain, plain_d = _frames(tmp_path)
    same, same_d = _frames(tmp_path, speed=0.09)
    fast, fast_d = _frames(tmp_path, speed=0.18)
    assert np.array_equal(plain_d, same_d), "0.09 m/s is the default"
    assert len(fast) == len(plain)
    assert all(np.allclose(a.pos, b.pos) and np.allclose(a.quat, b.quat) for a, b in zip(plain, fast))
    changed = np.flatnonzero(plain_d != fast_d)
    assert len(changed) >= 5, "the arc's keyframes"
    # each arc keyframe: ceil(d / 0.0015) steps at the default, ceil(d / 0.003) at twice the speed
    assert np.all(np.abs(fast_d[changed] - plain_d[changed] / 2) <= 1)
    assert fast[-1].end_step < plain[-1].end_step
