"""Snapshots of a running scene for the evaluator (`evaluation.state`), read from MjData.

The observer runs after every control step of an online session (`b2d bench recorder`), so every
lookup it can make once is made in ``__init__``: index arrays into qpos / qvel / xmat / site_xpos, the
constant states of fixed-base objects, and contact owners as integer codes. Per step it does a few
fancy-index reads and builds the evaluator's small Python objects from them.
"""

from __future__ import annotations

from functools import cached_property

import mujoco
import numpy as np

from evaluation.state import ObjectState, SceneState, TaskContext
from sim.scene.builder import Scene
from sim.tasks import task_context

POSE = np.arange(7)     # a free joint's qpos: position (3), then the wxyz quaternion (4)
TWIST = np.arange(6)    # its qvel: world linear velocity (3), then body-frame angular velocity (3)


def _frozen(a) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.flags.writeable = False
    return a


class SceneObserver:
    """Reads object poses/velocities, palm positions and contacts in evaluator terms."""

    def __init__(self, scene: Scene):
        self.scene = scene
        model = scene.model
        owner = np.full(model.nbody, "", dtype=object)   # body id -> evaluator name
        for name, bid in scene.object_body_ids.items():
            owner[bid] = name
        for joint in scene.joint_names:     # a touched door or key counts as its object
            owner[model.body(joint).id] = joint.split("/")[0]
        owner[model.body("table").id] = "table"
        for side, layout in scene.layout.sides.items():
            for body in layout.hand_bodies:
                owner[model.body(body).id] = f"{side}_hand"
        # contact owners as codes; _pair[a, b] indexes the sorted name pair in _pairs (-1: not a pair)
        names = sorted(set(owner) - {""})
        code = {"": 0, **{name: i + 1 for i, name in enumerate(names)}}
        self._geom_owner = np.array([code[owner[b]] for b in model.geom_bodyid], dtype=np.intp)
        self._pairs = [(a, b) for i, a in enumerate(names) for b in names[i + 1:]]
        index = {pair: k for k, pair in enumerate(self._pairs)}
        self._pair = np.full((len(code), len(code)), -1, dtype=np.intp)
        for a in names:
            for b in names:
                if a != b:
                    self._pair[code[a], code[b]] = index[(a, b) if a < b else (b, a)]
        self._sides = list(scene.layout.sides)
        self._wrist_sites = np.array([model.site(l.wrist_site).id for l in scene.layout.sides.values()],
                                     dtype=np.intp)
        self.robot_dof_idx = np.asarray(scene.robot_dof_adr, dtype=np.intp)   # arm and hand joints
        self.robot_qpos_idx = np.asarray(scene.robot_qpos_adr, dtype=np.intp)
        self._joint_names = list(scene.joint_qpos_adr)
        self._joint_adr = np.array([scene.joint_qpos_adr[j] for j in self._joint_names], dtype=np.intp)
        self._fixed = {n: ObjectState(pos=_frozen(model.body_pos[scene.object_body_ids[n]]),
                                      quat=_frozen(model.body_quat[scene.object_body_ids[n]]),
                                      lin_vel=_frozen(np.zeros(3)), ang_vel=_frozen(np.zeros(3)))
                       for n in scene.object_body_ids if n not in scene.object_qpos_adr}
        self._groups: dict[tuple, _ObjectGroup] = {}
        self._task_objects = self._group(tuple(scene.object_names))

    @cached_property
    def context(self) -> TaskContext:
        return task_context(self.scene.task)

    def _group(self, names: tuple) -> _ObjectGroup:
        group = self._groups.get(names)
        if group is None:
            group = self._groups[names] = _ObjectGroup(self.scene, names, self._fixed)
        return group

    def object_states(self, data: mujoco.MjData, names=None) -> dict[str, ObjectState]:
        group = self._group(tuple(names)) if names else self._task_objects
        return group.states(data)

    def object_motion_into(self, data: mujoco.MjData, names, pose: np.ndarray, lin_vel: np.ndarray,
                           ang_vel: np.ndarray) -> None:
        """The rows ``object_states(data, names)`` gives as (pos, quat), lin_vel, ang_vel, written into
        ``pose`` (n, 7), ``lin_vel`` and ``ang_vel`` (n, 3) with no per-object Python objects (the replay
        stores them every control step)."""
        self._group(tuple(names)).motion_into(data, pose, lin_vel, ang_vel)

    def object_pose_into(self, data: mujoco.MjData, out: np.ndarray) -> None:
        """The task objects' (pos, wxyz quat) rows, in ``scene.object_names`` order, written into ``out``
        (n_objects, 7): the values ``object_states`` gives, without building them."""
        self._task_objects.pose_into(data, out)

    def contacts(self, data: mujoco.MjData) -> frozenset[tuple[str, str]]:
        n = data.ncon
        if not n:
            return frozenset()
        # numpy lookups for all contacts at once: a Python loop over data.contact costs ~10 us per contact
        owners = self._geom_owner[data.contact.geom[:n]]
        found = set(self._pair[owners[:, 0], owners[:, 1]].tolist())
        found.discard(-1)
        return frozenset(self._pairs[k] for k in found)

    def state(self, data: mujoco.MjData) -> SceneState:
        hands = data.site_xpos[self._wrist_sites]
        return SceneState(
            time_s=float(data.time),
            objects=self.object_states(data),
            joints=dict(zip(self._joint_names, data.qpos[self._joint_adr].tolist())),
            hands=dict(zip(self._sides, hands)),
            table_height=self.scene.table_height,
            contacts=self.contacts(data),
            # motion diagnostics: two fancy-index copies, about 1 us each
            robot_qvel=data.qvel[self.robot_dof_idx],
            robot_effort=data.qfrc_actuator[self.robot_dof_idx],
        )


class _ObjectGroup:
    """Precomputed indices for reading one ordered list of objects: free ones from qpos/qvel/xmat in
    one fancy read each, fixed-base ones as their constant state (their pose in the world, at rest)."""

    def __init__(self, scene: Scene, names: tuple, fixed: dict[str, ObjectState]):
        self.names = names
        self.fixed = fixed
        free = [n for n in names if n not in fixed]
        self.free_names = free
        self.free_rows = np.array([names.index(n) for n in free], dtype=np.intp)
        self.fixed_rows = np.array([i for i, n in enumerate(names) if n in fixed], dtype=np.intp)
        self.fixed_pose = np.array([np.concatenate([fixed[n].pos, fixed[n].quat]) for n in names if n in fixed])
        self.pose_idx = np.array([scene.object_qpos_adr[n] + POSE for n in free], dtype=np.intp).reshape(-1, 7)
        self.twist_idx = np.array([scene.object_dof_adr[n] + TWIST for n in free], dtype=np.intp).reshape(-1, 6)
        self.bodies = np.array([scene.object_body_ids[n] for n in free], dtype=np.intp)
        self.all_free = len(free) == len(names)

    def states(self, data: mujoco.MjData) -> dict[str, ObjectState]:
        pose, twist = data.qpos[self.pose_idx], data.qvel[self.twist_idx]     # fresh arrays: rows are ours
        rot = data.xmat[self.bodies].reshape(-1, 3, 3)
        # free-joint qvel is (world linear velocity, body-frame angular velocity); the stacked matmul
        # gives the same bits as one rot @ w per object (checked: tests/teleop/test_recorder_store.py)
        spin = np.matmul(rot, twist[:, 3:, None])
        free = {name: ObjectState(pos=pose[i, :3], quat=pose[i, 3:], lin_vel=twist[i, :3], ang_vel=spin[i, :, 0])
                for i, name in enumerate(self.free_names)}
        if self.all_free:
            return free
        return {n: free[n] if n in free else self.fixed[n] for n in self.names}

    def motion_into(self, data: mujoco.MjData, pose: np.ndarray, lin_vel: np.ndarray, ang_vel: np.ndarray) -> None:
        twist = data.qvel[self.twist_idx]
        spin = np.matmul(data.xmat[self.bodies].reshape(-1, 3, 3), twist[:, 3:, None])   # as in states()
        rows = self.free_rows
        pose[rows] = data.qpos[self.pose_idx]
        lin_vel[rows] = twist[:, :3]
        ang_vel[rows] = spin[:, :, 0]
        if not self.all_free:
            pose[self.fixed_rows] = self.fixed_pose
            lin_vel[self.fixed_rows] = 0.0
            ang_vel[self.fixed_rows] = 0.0

    def pose_into(self, data: mujoco.MjData, out: np.ndarray) -> None:
        if self.all_free:
            data.qpos.take(self.pose_idx, out=out)
            return
        out[self.free_rows] = data.qpos[self.pose_idx]
        out[self.fixed_rows] = self.fixed_pose
