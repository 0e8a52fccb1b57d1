"""Meshes for tactile ray casting: one target per rigid body the fingers can touch.

Ray targets are task objects, each articulated link and the distractors, never the robot or the
table (reference implementation). A target's mesh is in its body's frame, so the sensor moves rays
into that frame with the body's pose each frame (`data.xpos`/`data.xmat` of `body`).
"""

from __future__ import annotations

from dataclasses import dataclass

import trimesh

from sim.scene.builder import Scene
from sim.scene.parts import Part, parts_mesh


@dataclass(frozen=True, eq=False)
class TactileTarget:
    name: str             # object name, or "<object>/<link>" for a link
    body: str             # MuJoCo body carrying the mesh's frame
    mesh: trimesh.Trimesh


def tactile_targets(scene: Scene) -> list[TactileTarget]:
    out = []
    for name, obj in scene.task.objects.items():
        out.append(TactileTarget(name, name, parts_mesh(obj.parts)))
        for link in obj.links:
            joint = f"{name}/{link.name}"
            out.append(TactileTarget(joint, joint, parts_mesh(link.parts)))
    for name, d in zip(scene.distractor_names, scene.sample.distractors):
        size = tuple(s * d["scale"] for s in d["size"])      # as the builder scales it
        out.append(TactileTarget(name, name, parts_mesh((Part(d["shape"], size),))))
    return out
