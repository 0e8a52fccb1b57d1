"""GR00T's meta/modality.json: which slice of `observation.state` and `action` is which body part
(state slices index `observation.state`, the joint positions; GR00T reads no other state key).

The vectors are cut into contiguous runs of the same part (left_arm, left_hand, right_arm, right_hand),
so the slices always tile each vector exactly, whatever order the joints come in; a part that appears
in two separate runs gets a numbered second name. Arm joints are the embodiment's arm description's
joints; every other joint of a side belongs to its hand."""

from __future__ import annotations

from lerobot_export.features import TASK_ANNOTATION, view_key
from lerobot_export.source import Layout

SIDES = ("left", "right")


def part_of(name: str, arm_joints: frozenset[str]) -> str:
    for side in SIDES:
        if name.startswith(f"{side}_"):
            return f"{side}_{'arm' if name[len(side) + 1:] in arm_joints else 'hand'}"
    return "arm" if name in arm_joints else "hand"


def slices(names: tuple[str, ...], arm_joints: frozenset[str]) -> dict[str, dict[str, int]]:
    """{part: {"start", "end"}} covering `names` in order, one entry per contiguous run."""
    out: dict[str, dict[str, int]] = {}
    start = 0
    for i in range(1, len(names) + 1):
        if i < len(names) and part_of(names[i], arm_joints) == part_of(names[start], arm_joints):
            continue
        part, n = part_of(names[start], arm_joints), 2
        key = part
        while key in out:
            key, n = f"{part}_{n}", n + 1
        out[key] = {"start": start, "end": i}
        start = i
    return out


def arm_joint_names(robot_type: str) -> frozenset[str]:
    from sim.embodiment.description import load_embodiment

    return frozenset(j.name for j in load_embodiment(robot_type).arm.joints)


def modality(layout: Layout) -> dict:
    arm = arm_joint_names(layout.robot_type)
    return {
        "state": slices(layout.state_names, arm),
        "action": slices(layout.action_names, arm),
        "video": {cam: {"original_key": view_key(cam)} for cam, _, _ in layout.views},
        "annotation": {TASK_ANNOTATION.removeprefix("annotation."): {}},
    }
