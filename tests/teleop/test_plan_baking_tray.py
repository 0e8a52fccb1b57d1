"""baking_tray_prep's plan on the stream path: the spatula picked with a flat pinch at its handle clear
of its blade, the brush with a pad pinch across its bristles (it stays lying along x, as on the tray),
the boxes with a pad pinch, all four onto the tray (b2d bench demos measures seeds 0-11: 12/12)."""

from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample, demonstration_seed
from sim.tasks import load_task
from teleop.demos import OPERATORS
from teleop.recorder import record_episode

TASK, EMBODIMENT, EPISODE = "baking_tray_prep", "iiwa7_sharpa", 0


def test_the_plan_sets_all_four_onto_the_tray():
    spec = load_task(TASK)
    at = {s["pick"]: (s.get("grasp"), s.get("grasp_point") is not None) for s in spec.demo_plan}
    assert at["spatula"] == ("flat_pinch", True) and at["brush"] == ("pinch", True)
    seed = demonstration_seed(TASK, EPISODE)
    scene = build_scene(spec, EMBODIMENT, demonstration_sample(spec, seed))
    rec = record_episode(scene, OPERATORS["stream"](), f"{EPISODE:04d}", seed)
    record = rec.extra["episode_record"]
    assert rec.success, f"final stages {record['stage_final']}, drop {record['drop']}"
    assert record["termination"] == "stable_success"
    assert not record["drop"] and not record["high_speed"]
