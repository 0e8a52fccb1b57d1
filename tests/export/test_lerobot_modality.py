"""GR00T's meta/modality.json: the state and action slices tile each vector exactly, part by part."""

import json

import pytest

from episodes.reader import open_episode
from lerobot_export import export_lerobot
from lerobot_export.modality import arm_joint_names, part_of, slices


def _tiles(parts: dict, names: list[str], arm: frozenset) -> None:
    """The slices, in start order, cover 0..len(names) without gap or overlap, and every name in a
    slice belongs to that slice's body part."""
    spans = sorted((s["start"], s["end"], part) for part, s in parts.items())
    assert spans[0][0] == 0 and spans[-1][1] == len(names)
    for (_, end, _), (start, _, _) in zip(spans, spans[1:]):
        assert end == start
    for start, end, part in spans:
        assert end > start
        assert {part_of(n, arm) for n in names[start:end]} == {part.rsplit("_", 1)[0] if part[-1].isdigit() else part}


def test_modality_slices_cover_state_and_action_exactly(export_episodes, tmp_path):
    export_lerobot(export_episodes[:1], tmp_path / "ds", "v2.1")
    modality = json.loads((tmp_path / "ds/meta/modality.json").read_text())
    info = json.loads((tmp_path / "ds/meta/info.json").read_text())
    arm = arm_joint_names(info["robot_type"])
    with open_episode(export_episodes[0]) as reader:
        state, action = reader.static("robot/joint_names"), reader.static("action/names")
    _tiles(modality["state"], state, arm)
    _tiles(modality["action"], action, arm)
    assert set(modality["state"]) == set(modality["action"]) == {"left_arm", "left_hand", "right_arm", "right_hand"}
    assert modality["state"]["left_arm"] == {"start": 0, "end": 6}       # the UR5's six joints lead
    assert {v["original_key"] for v in modality["video"].values()} == {
        k for k, f in info["features"].items() if f["dtype"] == "video"}
    assert "human.action.task_description" in modality["annotation"]
    assert "annotation.human.action.task_description" in info["features"]


@pytest.mark.parametrize("names", [
    ["left_a", "left_h1", "right_a", "right_h1", "right_h2"],
    ["left_a", "right_a", "left_h1", "right_h1", "left_h2"],      # parts interleaved: numbered runs
    ["a", "h1"],                                                  # one-armed, no side prefix
])
def test_slices_tile_any_joint_order(names):
    arm = frozenset({"a"})
    parts = slices(tuple(names), arm)
    _tiles(parts, names, arm)
