"""Build the executable scene S_e = Build(T, g_e): table, objects, distractors, lights, background
and the bimanual robot, as one compiled MuJoCo model."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import mujoco
import numpy as np

from sim import physics
from sim.embodiment import add_bimanual_robot
from sim.scene.objects import add_free_object, add_task_object, yaw_quat
from sim.scene.parts import Part, euler_quat
from sim.scene.sample import SceneSample, demonstration_sample, demonstration_seed
from sim.tasks import TaskSpec, load_task

OFFSCREEN_WIDTH, OFFSCREEN_HEIGHT = 640, 480   # the paper's camera resolution bounds every profile
PLACEMENT_GAP_M = 0.001
_BUILTIN = {"checker": mujoco.mjtBuiltin.mjBUILTIN_CHECKER, "gradient": mujoco.mjtBuiltin.mjBUILTIN_GRADIENT,
            "flat": mujoco.mjtBuiltin.mjBUILTIN_FLAT}


@dataclass
class Scene:
    """A compiled scene plus the name -> index maps the recorder, replay and renderer share."""

    model: mujoco.MjModel
    task: TaskSpec
    sample: SceneSample
    layout: object            # sim.embodiment.RobotLayout
    object_names: list[str]
    distractor_names: list[str]

    @cached_property
    def object_body_ids(self) -> dict[str, int]:
        return {n: self.model.body(n).id for n in self.object_names + self.distractor_names}

    @cached_property
    def free_object_names(self) -> list[str]:
        """Task objects and distractors with a free joint (fixed bases have none)."""
        fixed = {n for n, o in self.task.objects.items() if o.base == "fixed"}
        return [n for n in self.object_names + self.distractor_names if n not in fixed]

    @cached_property
    def object_qpos_adr(self) -> dict[str, int]:
        return {n: int(self.model.jnt_qposadr[self.model.joint(f"{n}_free").id]) for n in self.free_object_names}

    @cached_property
    def object_dof_adr(self) -> dict[str, int]:
        return {n: int(self.model.jnt_dofadr[self.model.joint(f"{n}_free").id]) for n in self.free_object_names}

    @cached_property
    def joint_names(self) -> list[str]:
        """Articulated-object joints, "<object>/<link>" (also their link bodies' names)."""
        return self.task.joint_names

    @cached_property
    def joint_qpos_adr(self) -> dict[str, int]:
        return {j: int(self.model.jnt_qposadr[self.model.joint(j).id]) for j in self.joint_names}

    @cached_property
    def joint_initial(self) -> dict[str, float]:
        return {f"{o.name}/{link.name}": link.joint.initial for o in self.task.objects.values() for link in o.links}

    @cached_property
    def robot_qpos_adr(self) -> np.ndarray:
        return np.array([self.model.jnt_qposadr[self.model.joint(j).id] for j in self.layout.joint_names])

    @cached_property
    def robot_dof_adr(self) -> np.ndarray:
        return np.array([self.model.jnt_dofadr[self.model.joint(j).id] for j in self.layout.joint_names])

    @property
    def table_height(self) -> float:
        return self.sample.table_height

    def home_data(self) -> mujoco.MjData:
        """Objects at their sampled poses with their joints at the task's initial values, robot at its
        home configuration, home targets held."""
        data = mujoco.MjData(self.model)
        data.qpos[self.robot_qpos_adr] = self.layout.home_qpos
        for joint, q in self.joint_initial.items():
            data.qpos[self.joint_qpos_adr[joint]] = q
        data.ctrl[:] = self.layout.home_ctrl
        mujoco.mj_forward(self.model, data)
        return data


def build_scene(task: TaskSpec, embodiment: str, sample: SceneSample, hand_model: str | None = None) -> Scene:
    """``hand_model``: "generated", "real" (the hand file's real_model MJCF) or None ($B2D_HAND_MODEL)."""
    spec = mujoco.MjSpec()
    spec.modelname = f"{task.name}__{embodiment}"
    physics.configure_options(spec)
    spec.visual.global_.offwidth = OFFSCREEN_WIDTH
    spec.visual.global_.offheight = OFFSCREEN_HEIGHT
    _add_background(spec, sample.background)
    _add_lighting(spec, sample.lighting)
    _add_table(spec, task, sample)
    frame_z: dict[str, float] = {}
    for name, obj in task.objects.items():
        x, y, yaw = sample.object_poses[name]
        # a fixed base sits on its support; a free one is dropped from just above it
        gap = 0.0 if obj.base == "fixed" else PLACEMENT_GAP_M
        support = (frame_z[obj.on] + task.objects[obj.on].support_height if obj.on is not None
                   else sample.table_height)
        frame_z[name] = support + obj.rest_height + gap
        add_task_object(spec, obj, (x, y, frame_z[name]), yaw_quat(yaw))
    distractor_names = []
    for i, d in enumerate(sample.distractors):
        name = f"distractor_{i}"
        size = [s * d["scale"] for s in d["size"]]
        z = sample.table_height + Part(d["shape"], tuple(size)).local_half_extents()[2] + PLACEMENT_GAP_M
        add_free_object(spec, name, d["shape"], size, d["mass"], 0.8, d["rgba"],
                        (d["xy"][0], d["xy"][1], z), yaw_quat(d["yaw_deg"]))
        distractor_names.append(name)
    layout = add_bimanual_robot(spec, embodiment, hand_model=hand_model)
    model = spec.compile()
    _perturb_cameras(model, sample.camera_offsets)
    return Scene(model, task, sample, layout, list(task.objects), distractor_names)


def _add_background(spec: mujoco.MjSpec, bg: dict) -> None:
    spec.add_texture(name="skybox", type=mujoco.mjtTexture.mjTEXTURE_SKYBOX,
                     builtin=mujoco.mjtBuiltin.mjBUILTIN_GRADIENT, rgb1=bg["sky_rgb1"],
                     rgb2=bg["sky_rgb2"], width=64, height=64)
    floor = spec.add_material(name="floor", rgba=[*bg["floor_rgb"], 1.0])
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[3, 3, 0.1],
                            material=floor.name)


def _add_lighting(spec: mujoco.MjSpec, lighting: dict) -> None:
    """Map the paper's distant/dome light ranges onto MuJoCo's directional light and headlight
    (normalised so the nominal sample gives a neutral, well exposed image)."""
    distant, dome = lighting["distant"], lighting["dome"]
    pitch, yaw = np.deg2rad(distant["pitch_deg"]), np.deg2rad(distant["yaw_deg"])
    direction = [np.cos(pitch) * np.sin(yaw), np.cos(pitch) * np.cos(yaw), np.sin(pitch)]
    strength = 0.6 * distant["intensity"] / 1250.0
    spec.worldbody.add_light(name="distant", type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
                             pos=[0, 0, 3], dir=[float(v) for v in direction],
                             diffuse=[float(c) * strength for c in distant["color"]],
                             specular=[0.1, 0.1, 0.1], castshadow=False)
    ambient = 0.35 * dome["intensity"] / 250.0 * 2.0 ** dome["exposure"]
    spec.visual.headlight.ambient = [float(c) * ambient for c in dome["color"]]
    spec.visual.headlight.diffuse = [0.3, 0.3, 0.3]
    spec.visual.headlight.specular = [0.05, 0.05, 0.05]


def _add_table(spec: mujoco.MjSpec, task: TaskSpec, sample: SceneSample) -> None:
    tex = sample.table_texture
    spec.add_texture(name="tabletop", type=mujoco.mjtTexture.mjTEXTURE_2D, builtin=_BUILTIN[tex["builtin"]],
                     rgb1=tex["rgb1"], rgb2=tex["rgb2"], width=128, height=128)
    material = spec.add_material(name="tabletop", texrepeat=[tex["repeat"], tex["repeat"]])
    material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "tabletop"
    sx, sy = task.table.size_xy
    h, t = sample.table_height, task.table.thickness
    table = spec.worldbody.add_body(name="table", pos=[0, 0, h - t / 2])
    table.add_geom(name="table_top", type=mujoco.mjtGeom.mjGEOM_BOX, size=[sx / 2, sy / 2, t / 2],
                   material="tabletop", friction=[task.table.friction, 0.01, 0.0005], condim=4)
    leg_h = (h - t) / 2
    for i, (lx, ly) in enumerate([(1, 1), (1, -1), (-1, 1), (-1, -1)]):
        table.add_geom(name=f"table_leg_{i}", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.025, 0.025, leg_h],
                       pos=[lx * (sx / 2 - 0.05), ly * (sy / 2 - 0.05), -t / 2 - leg_h],
                       rgba=[0.3, 0.3, 0.3, 1], contype=0, conaffinity=0)


def _min_rotation(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Quaternion of the smallest rotation taking unit vector a onto unit vector b."""
    quat = np.zeros(4)
    mujoco.mju_quatZ2Vec(quat, b)           # z -> b
    inv = np.zeros(4)
    mujoco.mju_quatZ2Vec(inv, a)            # z -> a
    mujoco.mju_negQuat(inv, inv)
    out = np.zeros(4)
    mujoco.mju_mulQuat(out, quat, inv)
    return out


def _perturb_cameras(model: mujoco.MjModel, offsets: dict[str, dict], look_distance_m: float = 1.0) -> None:
    """Camera-pose factor, in each camera's parent frame: translation, a change of the distance
    to the look-at point along the optical axis, a look-at target offset (the camera turns to
    keep looking at the shifted target) and a small roll-pitch-yaw. The stereo pair shares one
    sample, so its relative pose is preserved."""
    for cam, off in offsets.items():
        cid = model.camera(cam).id
        quat = model.cam_quat[cid].copy()
        axis = np.zeros(3)
        mujoco.mju_rotVecQuat(axis, np.array([0.0, 0.0, -1.0]), quat)   # optical axis
        target = model.cam_pos[cid] + axis * look_distance_m
        pos = model.cam_pos[cid] + np.asarray(off["pos"]) - axis * off.get("distance", 0.0)
        new_axis = target + np.asarray(off.get("target", [0.0, 0.0, 0.0])) - pos
        new_axis /= np.linalg.norm(new_axis)
        turned = np.zeros(4)
        mujoco.mju_mulQuat(turned, _min_rotation(axis, new_axis), quat)
        final = np.zeros(4)
        mujoco.mju_mulQuat(final, turned, np.asarray(euler_quat(off["rpy_deg"])))
        model.cam_pos[cid] = pos
        model.cam_quat[cid] = final


def demonstration_scene(task: str | TaskSpec, embodiment: str, index: int = 0) -> Scene:
    """The scene of a task's demonstration `index` on an embodiment (its seed and scene sample). `task`
    is a name or a spec; a spec (e.g. a task file with a changed layout or plan) keeps its name's seed."""
    spec = load_task(task) if isinstance(task, str) else task
    return build_scene(spec, embodiment, demonstration_sample(spec, demonstration_seed(spec.name, index)))
