"""The plan tried on fridge_wine_interhand_pour at stop 31 (4 of 12 seeds; the task file's plan since stop 32
opens the door further and hands the bottle back round its body), planned on seed 0's scene, for the tests of
the looks it needs."""

from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample, demonstration_seed
from sim.tasks import parse_task

from task_files import task_file_with_plan
from plan_runs import home_and_plan

TASK, EMBODIMENT = "fridge_wine_interhand_pour", "ur5_rh5dg2"
# open the door, take the bottle out by its neck and hand it to the right by its bottom, pour (kept in hand),
# hand it back, put it back through the front
PLAN = [{"hand": "left", "turn": "fridge/door", "to": 1.7, "speed": 0.15},
        {"hand": "left", "handover": "wine_bottle", "to_hand": "right", "at": [0.0, -0.12, 0.3], "pick_from": "front",
         "grasp": "side", "grasp_point": [0.0, 0.0, 0.1], "take_point": [0.0, 0.0, -0.13], "take_roll_deg": 120},
        {"hand": "right", "pour": "wine_bottle", "into": "glass", "hold": True, "tilt_deg": 62, "tilt_toward": [-1.0, 0.0]},
        {"hand": "right", "handover": "wine_bottle", "to_hand": "left", "at": [0.0, -0.12, 0.3],
         "take_point": [0.0, 0.0, 0.08]},
        {"hand": "left", "pick": "wine_bottle", "place": "fridge", "place_from": "front", "place_offset": [0.05, 0.02]}]


def planned_scene(steps: list[dict], tmp_path):
    """(scene, homed data, operator that has planned ``steps``) on seed 0's scene."""
    task = parse_task(task_file_with_plan(TASK, steps), tmp_path / "fridge.yaml")
    scene = build_scene(task, EMBODIMENT, demonstration_sample(task, demonstration_seed(TASK, 0)))
    data, op = home_and_plan(scene)
    return scene, data, op
