"""Pick field `thin_grasp` (palm grasp): the hand closes to its hand file's targets for a thin object
(`tabletop_grasp.thin_close`) where it declares them. The Wuji's palm-down grasp, eased to 0.7 of its power
grasp for a 6.4 cm jar, touched medicine_shoebox_pack's 4 cm pill bottle and 4.4 cm oil without lifting
them; its thin_close curls the four fingers further. A hand that declares none closes as without the field,
and the check refuses it off a palm grasp."""

import dataclasses

import numpy as np
import pytest

from sim.demo_plan import PlanScope, parse_plan
from sim.embodiment import load_embodiment
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene
from sim.tasks import load_task
from teleop.recorder import home
from teleop.scripted_operator import ScriptedOperator

TASK = "medicine_shoebox_pack"
PICK = {"hand": "right", "pick": "pill_bottle", "place": "table", "place_offset": [0.32, -0.2]}


def _plan(steps):
    task = load_task(TASK)
    return parse_plan("t.yaml", {"demo_plan": steps}, PlanScope(task.objects, task.zones, task.points))


def _right_hand_targets(embodiment: str, step: dict) -> list[np.ndarray]:
    scene = demonstration_scene(TASK, embodiment, 0)
    scene.task = dataclasses.replace(scene.task, demo_plan=_plan([step]))     # not load_task's cached one
    op = ScriptedOperator()
    op.reset(scene, home(scene))
    return [np.asarray(f.hand, float) for f in op.sides["right"]["timeline"].frames]


@pytest.mark.parametrize("fields", [{"grasp": "pinch"}, {"grasp": "flat_pinch"}, {"thin_grasp": "yes"}])
def test_check_refuses_thin_grasp_off_a_palm_grasp(fields):
    with pytest.raises(SpecError, match=r"demo_plan\[0\]\.thin_grasp"):
        _plan([{**PICK, "thin_grasp": True, **fields}])


def test_the_wuji_closes_its_fingers_further():
    thin = load_embodiment("ur5_wuji").hand.tabletop_grasp.thin_close
    assert thin and all(name.split("_")[0] in ("index", "middle", "ring", "little") for name in thin)
    plain = _right_hand_targets("ur5_wuji", PICK)
    targets = _right_hand_targets("ur5_wuji", {**PICK, "thin_grasp": True})
    assert len(plain) == len(targets)
    changed = [i for i, (a, b) in enumerate(zip(plain, targets)) if not np.allclose(a, b)]
    assert changed and max(np.abs(targets[i] - plain[i]).max() for i in changed) > 0.1


def test_a_hand_without_thin_targets_closes_as_before():
    assert not load_embodiment("panda_orca").hand.tabletop_grasp
    plain = _right_hand_targets("panda_orca", PICK)
    targets = _right_hand_targets("panda_orca", {**PICK, "thin_grasp": True})
    assert len(plain) == len(targets) and all(np.allclose(a, b) for a, b in zip(plain, targets))
