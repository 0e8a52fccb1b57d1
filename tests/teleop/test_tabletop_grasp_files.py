"""Hand files' `tabletop_grasp` entries (the scripted operator's palm-down grasp of a fruit-sized object)."""

from sim.embodiment.description import load_embodiment
from sim.scene.builder import demonstration_scene
from teleop.recorder import record_episode
from teleop.scripted_operator import hand_grasp
from teleop.scripted_stream import ScriptedStreamOperator


def test_shadow_declares_an_opposed_thumb_grasp():
    hand = load_embodiment("ur5_shadow").hand
    grasp = hand_grasp(hand, "right")
    assert grasp is hand.tabletop_grasp and grasp.close["THJ4"] > 1.0     # the thumb under the palm
    assert hand_grasp(hand, "left").centre[0] == -grasp.centre[0]


def test_shadow_lifts_an_apple_off_the_table():
    """fruit_bowl_loading on UR5+Shadow through the stream (as recorded): the left hand's first step
    picks apple_1. With the power grasp (no `tabletop_grasp`) the curling fingers rolled the apple
    under the wrist: 0.2 cm."""
    scene = demonstration_scene("fruit_bowl_loading", "ur5_shadow", 0)
    rec = record_episode(scene, ScriptedStreamOperator(), "apple", 0, max_steps=400)
    z = rec.object_pose[:, rec.object_names.index("apple_1"), 2]
    assert z.max() - z[0] > 0.1, f"apple_1 only rose {1000 * (z.max() - z[0]):.0f} mm"
