"""Build a task's scene on an embodiment and let it settle with the robot holding its home pose."""

from __future__ import annotations

import time
from dataclasses import dataclass

import mujoco
import numpy as np

from evaluation.geometry import vertical_half_extent
from sim import physics
from sim.scene.builder import Scene, build_scene
from sim.scene.sample import demonstration_sample
from sim.scene.state import SceneObserver
from sim.tasks import load_task

SETTLE_STEPS = physics.CONTROL_HZ      # 1 s


@dataclass
class Settled:
    scene: Scene
    data: mujoco.MjData
    start: dict          # object name -> ObjectState before settling
    end: dict            # ... after
    joints: dict         # joint -> value after settling
    build_s: float
    settle_s: float

    def object_contacts(self) -> list[tuple[str, str, float]]:
        """Contacts that touch a task object (a base or a link): (object, other body, distance);
        the other body is an object, 'table', 'world' or a robot body."""
        model = self.scene.model
        owner = {self.scene.object_body_ids[n]: n for n in self.scene.object_names}
        owner.update({model.body(j).id: j.split("/")[0] for j in self.scene.joint_names})
        out = []
        for c in self.data.contact[: self.data.ncon]:
            b1, b2 = model.geom_bodyid[c.geom1], model.geom_bodyid[c.geom2]
            for a, b in ((b1, b2), (b2, b1)):
                if a in owner:
                    out.append((owner[a], owner.get(b, model.body(b).name or "world"), float(c.dist)))
                    break
        return out

    def bottom_clearance(self, name: str) -> float:
        """Bounding-box bottom above the tabletop after settling (negative: sunk into it)."""
        o = self.end[name]
        half = self.scene.task.objects[name].half_extents
        return float(o.pos[2] - vertical_half_extent(o.quat, half) - self.scene.table_height)


def settle(task: str, embodiment: str, seed: int = 0, steps: int = SETTLE_STEPS) -> Settled:
    spec = load_task(task)
    t0 = time.perf_counter()
    scene = build_scene(spec, embodiment, demonstration_sample(spec, seed))
    t1 = time.perf_counter()
    data = scene.home_data()
    observer = SceneObserver(scene)
    start = observer.object_states(data)
    for _ in range(steps):
        physics.step_control(scene.model, data, scene.layout.home_ctrl)
    t2 = time.perf_counter()
    return Settled(scene, data, start, observer.object_states(data), observer.state(data).joints, t1 - t0, t2 - t1)
