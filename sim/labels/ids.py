"""Stable label ids: which object, robot part or table every geom of a compiled scene belongs to.

Instances are the scene's objects in a fixed order (task objects in the task file's order, then the
distractors), numbered from 1; 0 is "no object" (robot, table, background). Semantic classes are
0 = background, then the scene parts (table, robot base, each arm and hand) and then one class per
object category in order of first appearance. A geom belongs to the nearest body up its ancestry
that is an object's root body or a listed part body, so articulated links (bodies "<object>/<link>")
label as their object. Everything depends only on the model and the declared order, so two builds of
the same scene give identical ids.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Mapping, Sequence

import mujoco
import numpy as np

BACKGROUND = "background"
DISTRACTOR_CATEGORY = "distractor"
_NUMBERED = re.compile(r"^(.+?)_\d+$")


def object_category(name: str) -> str:
    """An object's category from its name: a trailing "_<number>" names one of several alike
    (lemon_1, lemon_2 -> lemon); any other name is its own category."""
    match = _NUMBERED.match(name)
    return match.group(1) if match else name


@dataclass(frozen=True)
class LabelIds:
    semantic_names: tuple[str, ...]     # semantic id -> class name; 0 = background
    instance_names: tuple[str, ...]     # instance id -> object name; 0 = "" (no object)
    instance_semantic: np.ndarray       # [N+1] semantic id of each instance (0 for id 0)
    instance_body: np.ndarray           # [N+1] root body id of each instance (-1 for id 0)
    geom_semantic: np.ndarray           # [ngeom] uint8
    geom_instance: np.ndarray           # [ngeom] uint16

    @property
    def object_names(self) -> tuple[str, ...]:
        return self.instance_names[1:]

    def instance_geoms(self, instance: int) -> np.ndarray:
        return np.flatnonzero(self.geom_instance == instance)

    def semantic_json(self) -> dict[str, str]:
        return {str(i): name for i, name in enumerate(self.semantic_names)}

    def instances_json(self) -> dict[str, dict]:
        return {str(i): {"name": name, "category": self.semantic_names[self.instance_semantic[i]],
                         "semantic_id": int(self.instance_semantic[i])}
                for i, name in enumerate(self.instance_names) if i}

    @classmethod
    def build(cls, model: mujoco.MjModel, objects: Sequence[tuple[str, str]],
              parts: Mapping[str, Sequence[str]]) -> "LabelIds":
        """`objects`: (root body name, category) in instance order; `parts`: semantic class ->
        body names (table, robot parts), in semantic-id order."""
        categories = list(dict.fromkeys(category for _, category in objects))
        clash = sorted(set(categories) & (set(parts) | {BACKGROUND}))
        if clash:
            raise ValueError(f"object categories {clash} collide with the scene classes {[BACKGROUND, *parts]}")
        semantic = (BACKGROUND, *parts, *categories)
        if len(semantic) > 256:
            raise ValueError(f"{len(semantic)} semantic classes do not fit the uint8 labels (at most 256)")
        if len(objects) >= 2 ** 16:
            raise ValueError(f"{len(objects)} objects do not fit the uint16 instance labels")
        body_label: dict[int, tuple[int, int]] = {}    # body id -> (semantic id, instance id)
        for cls_id, (name, bodies) in enumerate(parts.items(), start=1):
            for body in bodies:
                body_label[_body_id(model, body, f"part '{name}'")] = (cls_id, 0)
        instance_semantic, instance_body = [0], [-1]
        for inst, (name, category) in enumerate(objects, start=1):
            bid = _body_id(model, name, "object")
            body_label[bid] = (semantic.index(category), inst)
            instance_semantic.append(semantic.index(category))
            instance_body.append(bid)
        geom_semantic = np.zeros(model.ngeom, np.uint8)
        geom_instance = np.zeros(model.ngeom, np.uint16)
        for g in range(model.ngeom):
            body = int(model.geom_bodyid[g])
            while body > 0 and body not in body_label:   # climb to the nearest labelled ancestor
                body = int(model.body_parentid[body])
            geom_semantic[g], geom_instance[g] = body_label.get(body, (0, 0))
        return cls(semantic, ("", *(name for name, _ in objects)), np.array(instance_semantic, np.uint8),
                   np.array(instance_body, np.int64), geom_semantic, geom_instance)

    @classmethod
    def from_scene(cls, scene) -> "LabelIds":
        """Ids of a built task scene (`sim.scene.builder.Scene`): its objects then distractors, the
        table, the robot's torso and each side's arm and hand bodies."""
        layout = scene.layout
        # semantic-id order: where geoms overlap in the occupancy grid the later class wins
        parts = {"table": ["table"], "robot_base": [layout.torso_body]}
        for side in ("left", "right"):
            parts[f"robot_{side}_arm"] = layout.sides[side].arm_bodies
            parts[f"robot_{side}_hand"] = layout.sides[side].hand_bodies
        objects = [(n, object_category(n)) for n in scene.object_names]
        objects += [(n, DISTRACTOR_CATEGORY) for n in scene.distractor_names]
        return cls.build(scene.model, objects, parts)


def _body_id(model: mujoco.MjModel, name: str, what: str) -> int:
    try:
        return int(model.body(name).id)
    except KeyError:
        raise ValueError(f"{what}: no body named '{name}' in the compiled model") from None
