"""Snapshots of a running scene for the evaluator (`evaluation.state`), read from MjData."""

from __future__ import annotations

from functools import cached_property

import mujoco
import numpy as np

from evaluation.state import ObjectState, SceneState, TaskContext
from sim.scene.builder import Scene
from sim.tasks import task_context


class SceneObserver:
    """Reads object poses/velocities, palm positions and contacts in evaluator terms."""

    def __init__(self, scene: Scene):
        self.scene = scene
        model = scene.model
        self._owner = np.full(model.nbody, "", dtype=object)   # body id -> evaluator name
        for name, bid in scene.object_body_ids.items():
            self._owner[bid] = name
        for joint in scene.joint_names:     # a touched door or key counts as its object
            self._owner[model.body(joint).id] = joint.split("/")[0]
        self._owner[model.body("table").id] = "table"
        for side, layout in scene.layout.sides.items():
            for body in layout.hand_bodies:
                self._owner[model.body(body).id] = f"{side}_hand"
        self._wrist_sites = {side: model.site(l.wrist_site).id for side, l in scene.layout.sides.items()}
        self._robot_dofs = np.asarray(scene.robot_dof_adr, dtype=np.intp)   # arm and hand joints

    @cached_property
    def context(self) -> TaskContext:
        return task_context(self.scene.task)

    def object_states(self, data: mujoco.MjData, names=None) -> dict[str, ObjectState]:
        out = {}
        for name in names or self.scene.object_names:
            if name not in self.scene.object_qpos_adr:     # a fixed base: its pose in the world, at rest
                bid = self.scene.object_body_ids[name]
                model = self.scene.model
                out[name] = ObjectState(pos=model.body_pos[bid].copy(), quat=model.body_quat[bid].copy(),
                                        lin_vel=np.zeros(3), ang_vel=np.zeros(3))
                continue
            qa, da = self.scene.object_qpos_adr[name], self.scene.object_dof_adr[name]
            # free-joint qvel is (world linear velocity, body-frame angular velocity)
            ang_local = data.qvel[da + 3: da + 6]
            rot = data.xmat[self.scene.object_body_ids[name]].reshape(3, 3)
            out[name] = ObjectState(pos=data.qpos[qa: qa + 3].copy(), quat=data.qpos[qa + 3: qa + 7].copy(),
                                    lin_vel=data.qvel[da: da + 3].copy(), ang_vel=rot @ ang_local)
        return out

    def contacts(self, data: mujoco.MjData) -> frozenset[tuple[str, str]]:
        if not data.ncon:
            return frozenset()
        # one numpy lookup for all contacts: a Python loop over data.contact costs ~10 us per contact
        owners = self._owner[self.scene.model.geom_bodyid[data.contact.geom[: data.ncon]]]
        return frozenset(tuple(sorted((a, b))) for a, b in owners if a and b and a != b)

    def state(self, data: mujoco.MjData) -> SceneState:
        return SceneState(
            time_s=float(data.time),
            objects=self.object_states(data),
            joints={j: float(data.qpos[adr]) for j, adr in self.scene.joint_qpos_adr.items()},
            hands={side: data.site_xpos[sid].copy() for side, sid in self._wrist_sites.items()},
            table_height=self.scene.table_height,
            contacts=self.contacts(data),
            # motion diagnostics: two fancy-index copies, about 1 us each
            robot_qvel=data.qvel[self._robot_dofs],
            robot_effort=data.qfrc_actuator[self._robot_dofs],
        )
