"""Adds a bimanual arm+hand robot to an existing ``mujoco.MjSpec`` from the catalog descriptions.

Everything is built in code from the description (no XML, no meshes): bodies, hinge joints, geoms
and explicit inertials; position servos for every actuated DoF; joint equalities for coupled (mimic)
hand joints; contact exclusions between adjacent links; the wrist site, the tactile pad sites and pad
geoms; the six cameras. Names are ``{side}_{vendor name}``.

Servo gain rule (documented in the report and tested): for a joint with real max torque ``effort``
and max speed ``v_max``

* ``kp = effort / e_sat``: the servo applies its full torque at a tracking error ``e_sat``
  (``servo_error_at_full_effort`` of the arm / hand file; 0.05 rad arms, 0.1 rad hands);
* motor damping ``d = effort / v_max`` on the driven joint (added to the file's joint damping): with
  the servo saturated the joint torque is ``effort - d qdot``, the linear torque-speed line of a
  geared motor (full torque at rest, none at the no-load speed ``v_max``), so a step command is
  tracked at (or below) the real joint speed whatever its size. It must be joint damping, not the
  servo's ``kv``: MuJoCo clamps ``kp e - kv qdot`` as a whole, so a large step keeps the force at
  ``effort`` until ``qdot ~ kp e / kv`` (fingers reached 5x their real speed that way);
* ``kv = max(0, 2 sqrt(kp I) - d)``: together with ``d`` at least critically damped for the
  joint-space inertia ``I`` at home (Pinocchio CRBA for arms incl. the hand payload and armature;
  distal links plus armature for fingers);
* ``forcerange = +-effort``, ``ctrlrange = joint range``.

Robot bodies are gravity compensated (``gravcomp = 1``): real arm and hand controllers compensate
gravity, and it keeps the servo error free of a gravity offset.
"""

from __future__ import annotations

import functools
import logging
import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from .cameras import add_cameras
from .description import (EmbodimentDescription, GeomSpec, HandDescription, LinkSpec, Transform,
                          coupled_position, load_embodiment, mat_to_quat)
from .kinematics import ArmKinematics, axis_rotation, hand_link_poses
from .mirror import side_links, side_transform
from .real_model import add_real_actuators, attach_real_hand
from .real_model_file import requested_hand_model
from .tactile_block import side_pad

log = logging.getLogger(__name__)

PAD_GEOM_SUFFIX = "_pad"   # the contact-pad geom of tactile site "s" is "s_pad" (tactile.rig finds it so)
SIDES = ("left", "right")
_GEOM_TYPES = {
    "capsule": mujoco.mjtGeom.mjGEOM_CAPSULE, "box": mujoco.mjtGeom.mjGEOM_BOX,
    "sphere": mujoco.mjtGeom.mjGEOM_SPHERE, "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
    "ellipsoid": mujoco.mjtGeom.mjGEOM_ELLIPSOID,
}
PAD_THICKNESS_M = 0.002
# stiff joint limits (time constant 2.4 physics steps): a saturated servo pushing a light finger into
# its stop should not overshoot by more than about 0.01 rad
LIMIT_SOLREF = (0.005, 1.0)
# hand links whose origin is this close to the hand base (palm, thumb base and proximal) never get
# meaningful contact with the last two arm links at the wrist
WRIST_NEAR_M = 0.06
PAD_RGBA = (0.12, 0.12, 0.14, 1.0)
TORSO_RGBA = (0.35, 0.36, 0.4, 1.0)


@dataclass
class SideLayout:
    side: str                 # "left" | "right"
    arm_joints: list[str]     # MuJoCo joint names, chain order
    hand_joints: list[str]    # all hand joints, incl. coupled ones
    arm_actuators: list[str]
    hand_actuators: list[str]
    wrist_site: str           # palm-centre grasp frame site
    tactile_sites: list[str]  # MuJoCo site names of the pads
    tactile_bodies: dict[str, str]  # site -> attach body (prefixed)
    hand_bodies: list[str]    # all bodies of the hand (for contact queries)
    arm_bodies: list[str] = field(default_factory=list)
    hand_base: str = ""       # the hand's base (palm) body
    camera: str = ""          # wrist camera


@dataclass
class RobotLayout:
    embodiment: str
    sides: dict[str, SideLayout]
    actuator_names: list[str]   # ctrl order: left arm, left hand, right arm, right hand
    joint_names: list[str]      # robot joints in qpos order
    home_ctrl: np.ndarray       # (nu,) home targets
    home_qpos: np.ndarray       # (len(joint_names),)
    cameras: list[str] = field(default_factory=list)
    torso_body: str = "torso"
    hand_model: str = "generated"   # "generated" or "real" (recorded with each episode: replay rebuilds it)
    _kin: dict = field(default_factory=dict, repr=False)

    def arm_kinematics(self, side: str) -> ArmKinematics:
        if side not in self._kin:
            raise ValueError(f"unknown side {side!r}; valid: {list(self._kin)}")
        return self._kin[side]

    def apply_home(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Put the robot joints at home and its actuators on the home targets (other dofs untouched)."""
        for name, q in zip(self.joint_names, self.home_qpos):
            data.qpos[model.joint(name).qposadr[0]] = q
            data.qvel[model.joint(name).dofadr[0]] = 0.0
        data.ctrl[self.actuator_ids(model)] = self.home_ctrl
        mujoco.mj_forward(model, data)

    def actuator_ids(self, model: mujoco.MjModel) -> np.ndarray:
        return np.array([model.actuator(n).id for n in self.actuator_names])

    def qpos_ids(self, model: mujoco.MjModel) -> np.ndarray:
        return np.array([model.joint(n).qposadr[0] for n in self.joint_names])


# --------------------------------------------------------------------------------------------

def _add_geom(body: mujoco.MjsBody, g: GeomSpec, name: str | None = None) -> mujoco.MjsGeom:
    geom = body.add_geom(type=_GEOM_TYPES[g.type])
    if name:
        geom.name = name
    if g.fromto is not None:
        a, b = g.fromto[:3], g.fromto[3:]
        L = float(np.linalg.norm(b - a))
        geom.pos = (a + b) / 2
        u = (b - a) / L
        # rotation taking z to u
        v = np.cross([0.0, 0.0, 1.0], u)
        s, c = np.linalg.norm(v), u[2]
        rot = np.eye(3) if s < 1e-12 else axis_rotation(v / s, math.atan2(s, c))
        geom.quat = mat_to_quat(rot)
        geom.size = [g.size[0], L / 2, 0]
    else:
        geom.pos = g.pos
        geom.quat = mat_to_quat(g.rot)
        size = list(g.size) + [0.0] * (3 - len(g.size))
        geom.size = size
    if g.friction is not None:
        geom.friction = list(g.friction)
    if g.condim is not None:
        geom.condim = g.condim
    if g.rgba is not None:
        geom.rgba = list(g.rgba)
    return geom


def _angle_unit(spec: mujoco.MjSpec) -> float:
    """MjSpec converts joint ranges with the compiler's angle unit (degrees by default)."""
    return 180.0 / math.pi if spec.compiler.degree else 1.0


def _add_link(parent: mujoco.MjsBody, link: LinkSpec, prefix: str, origin: Transform | None = None,
              unit: float = 1.0) -> mujoco.MjsBody:
    T = origin if origin is not None else link.origin
    body = parent.add_body(name=prefix + link.name, pos=T.pos, quat=T.quat)
    body.explicitinertial = True
    body.mass = link.inertial.mass
    body.ipos = link.inertial.com
    body.inertia = link.inertial.inertia
    body.gravcomp = 1.0
    for j in link.joints:
        body.add_joint(
            name=prefix + j.name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=j.axis,
            range=[j.range[0] * unit, j.range[1] * unit], limited=mujoco.mjtLimited.mjLIMITED_TRUE,
            armature=j.armature, damping=j.damping, frictionloss=j.frictionloss,
            solref_limit=list(LIMIT_SOLREF),
        )
    for g in link.geoms:
        _add_geom(body, g)
    return body


def _position_actuator(spec: mujoco.MjSpec, name: str, joint: str, rng, effort: float, kp: float, kv: float):
    act = spec.add_actuator(name=name, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    act.set_to_position(kp=kp, kv=kv)
    act.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
    act.ctrlrange = list(rng)
    act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
    act.forcerange = [-effort, effort]
    return act


def servo_gains(effort: float, v_max: float, inertia: float, e_sat: float) -> tuple[float, float, float]:
    """The gain rule of the module docstring: (kp, kv, motor damping)."""
    kp = effort / e_sat
    damping = effort / v_max
    kv = max(0.0, 2.0 * math.sqrt(kp * inertia) - damping)
    return kp, kv, damping


def _add_motor_damping(spec: mujoco.MjSpec, joint: str, damping: float) -> None:
    j = spec.joint(joint)
    d = np.array(j.damping, dtype=float)
    d[0] += damping
    j.damping = d


def _finger_inertia(hand: HandDescription, joint_name: str) -> float:
    """Inertia about an actuated finger joint's axis of the links it moves (q = 0) plus armature."""
    poses = hand_link_poses(hand)
    links = list(hand.links)
    owner = next(lk for lk in links if any(j.name == joint_name for j in lk.joints))
    j = hand.joint(joint_name)
    T0 = poses[owner.name]
    axis = T0.rot @ j.axis
    # descendants of the owner link
    moved, frontier = {owner.name}, [owner.name]
    while frontier:
        n = frontier.pop()
        for lk in links:
            if lk.parent == n and lk.name not in moved:
                moved.add(lk.name)
                frontier.append(lk.name)
    total = j.armature
    for lk in links:
        if lk.name in moved:
            T = poses[lk.name]
            c = T.pos + T.rot @ lk.inertial.com - T0.pos
            r_perp = c - axis * (c @ axis)
            I = T.rot @ np.diag(lk.inertial.inertia) @ T.rot.T
            total += lk.inertial.mass * (r_perp @ r_perp) + axis @ I @ axis
    return total


def _hand_home(hand: HandDescription) -> dict[str, float]:
    q = {}
    for j in hand.joints:
        q[j.name] = float(np.clip(hand.home.get(j.name, 0.0), *j.range))
    for c in hand.couplings:
        if c.joint not in hand.home:
            m = q[c.master]
            q[c.joint] = float(np.clip(coupled_position(c.polycoef, m), *hand.joint(c.joint).range))
    return q


@functools.lru_cache(maxsize=None)
def home_arm_angles(name: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Home arm joint angles per side: IK of the embodiment's home wrist pose (left mirrored),
    seeded with the arm file's elbow-up seed (deterministic)."""
    emb = load_embodiment(name)
    out = []
    for side in SIDES:
        if emb.home_arm is not None:
            out.append(tuple(float(v) for v in emb.home_arm[side]))
            continue
        kin = ArmKinematics(emb.arm, emb.mounts[side], emb.hand, side)
        target = side_transform(emb.home_wrist, side)
        seeds = [emb.home_seed[side]] if emb.home_seed else []
        seeds.append(emb.arm.home_seed[side])
        best = None
        for seed in seeds:      # the embodiment's own seed first: it names the configuration wanted
            r = kin.ik(target.pos, target.quat, seed, max_iters=500)
            if r.success:
                best = r
                break
        if best is None:
            raise ValueError(f"{emb.path}: field 'home.right_wrist': the {side} arm cannot reach the home "
                             f"wrist pose {target.pos.tolist()} (IK failed from every home seed: "
                             f"the embodiment's, then the arm's)")
        out.append(tuple(float(v) for v in best.q))
    return out[0], out[1]


def _torso_transform(emb: EmbodimentDescription) -> tuple[Transform, np.ndarray]:
    size = np.asarray(emb.torso.get("size", [0.14, 0.09, 0.5]), float)
    pos = np.asarray(emb.torso.get("pos", [0.0, -0.62, 0.5]), float)
    return Transform(pos, np.eye(3)), size


def add_bimanual_robot(spec: mujoco.MjSpec, embodiment: str, hand_model: str | None = None) -> RobotLayout:
    """Add both arms + hands, the shared torso and the six cameras to ``spec.worldbody``.

    ``hand_model``: ``"generated"`` (the hand file's geometry) or ``"real"`` (its ``real_model:`` MJCF,
    see ``real_model.py``); None reads ``$B2D_HAND_MODEL`` (default generated)."""
    real_hand = requested_hand_model(hand_model) == "real"
    emb = load_embodiment(embodiment)
    arm, hand = emb.arm, emb.hand
    world = spec.worldbody
    unit = _angle_unit(spec)
    torso_tf, torso_size = _torso_transform(emb)
    torso = world.add_body(name="torso", pos=torso_tf.pos, quat=torso_tf.quat)
    torso.add_geom(name="torso_column", type=mujoco.mjtGeom.mjGEOM_BOX, size=torso_size, rgba=list(TORSO_RGBA))
    # cross bar carrying both arm bases (just below them)
    bar_z = np.mean([emb.mounts[s].pos[2] for s in SIDES]) - 0.02 - torso_tf.pos[2]
    bar_y = np.mean([emb.mounts[s].pos[1] for s in SIDES]) - torso_tf.pos[1]
    half_w = max(abs(emb.mounts[s].pos[0]) for s in SIDES) + 0.08
    torso.add_geom(name="torso_bar", type=mujoco.mjtGeom.mjGEOM_BOX, pos=[0, bar_y / 2, bar_z],
                   size=[half_w, abs(bar_y) / 2 + 0.06, 0.018], rgba=list(TORSO_RGBA))
    torso.add_geom(name="torso_mast", type=mujoco.mjtGeom.mjGEOM_CAPSULE,
                   fromto=[0, 0.05, torso_size[2], 0, 0.05, torso_size[2] + 0.2], size=[0.025, 0, 0],
                   rgba=list(TORSO_RGBA))
    inv_torso = torso_tf.inverse()
    home_left, home_right = home_arm_angles(emb.name)
    home_arm = {"left": np.array(home_left), "right": np.array(home_right)}
    hand_q = _hand_home(hand)
    hand_poses = hand_link_poses(hand)

    sides: dict[str, SideLayout] = {}
    palms: dict[str, mujoco.MjsBody] = {}
    kin: dict[str, ArmKinematics] = {}
    actuators: list[str] = []
    joints: list[str] = []
    ctrl: list[float] = []
    qpos: list[float] = []
    excludes: list[tuple[str, str]] = []
    for side in SIDES:
        p = f"{side}_"
        mount = emb.mounts[side]
        k = ArmKinematics(arm, mount, hand, side)
        kin[side] = k
        # ---- arm
        base_link = arm.links[0]
        body = _add_link(torso, base_link, p, origin=inv_torso @ mount, unit=unit)
        excludes.append(("torso", body.name))
        arm_bodies = [body.name]
        for link in arm.links[1:]:
            child = _add_link(body, link, p, unit=unit)
            excludes.append((body.name, child.name))
            body = child
            arm_bodies.append(body.name)
        last_arm = body
        excludes += [(p + a, p + b) for a, b in arm.contact_exclude]
        # ---- hand (mirrored on the left), or the real model of this side
        links = side_links(hand.links, side)
        hand_base_tf = arm.flange @ side_transform(hand.mount, side)
        bodies = {}
        side_q = hand_q
        real = None
        if real_hand:
            real = attach_real_hand(spec, last_arm, hand, side, hand_base_tf, p)
            bodies = real.bodies
            side_q = {j: float(np.clip(q, *real.joint_range[j])) for j, q in hand_q.items()}
            # pads sit on the alias bodies: keep them off the model body the finger body hangs on
            excludes += [(b.name, b.parent.parent.name) for b in bodies.values() if b.parent.parent.name != "world"]
        else:
            for link in links:
                parent = bodies[link.parent] if link.parent else last_arm
                origin = hand_base_tf if link.parent is None else None
                b = _add_link(parent, link, p, origin=origin, unit=unit)
                excludes.append((parent.name, b.name))
                bodies[link.name] = b
            excludes += [(p + a, p + b) for a, b in hand.contact_exclude]
        palm = bodies[links[0].name]
        palms[side] = palm
        ws = side_transform(hand.wrist_site, side)
        palm.add_site(name=f"{p}wrist_site", pos=ws.pos, quat=ws.quat, size=[0.006, 0.006, 0.006],
                      rgba=[0.9, 0.2, 0.2, 0.5], group=4)
        tactile_sites, tactile_bodies = [], {}
        for s in hand.tactile.sites:
            pad = side_pad(s.pad, side)
            R = np.column_stack([pad.axis, np.cross(pad.normal, pad.axis), pad.normal])  # x along finger, z out
            b = bodies[emb.tactile_attach.get(s.name, s.attach_body)]
            sname = p + s.name
            b.add_site(name=sname, pos=pad.center, quat=mat_to_quat(R), type=mujoco.mjtGeom.mjGEOM_BOX,
                       size=[pad.length / 2, pad.width / 2, PAD_THICKNESS_M / 2], rgba=[0.1, 0.8, 0.3, 0.4], group=4)
            g = b.add_geom(name=f"{sname}{PAD_GEOM_SUFFIX}", type=mujoco.mjtGeom.mjGEOM_BOX,
                           pos=pad.center - pad.normal * PAD_THICKNESS_M, quat=mat_to_quat(R),
                           size=[pad.length / 2, pad.width / 2, PAD_THICKNESS_M], rgba=list(PAD_RGBA))
            g.friction = list(hand.tactile.pad_friction)
            g.condim = hand.tactile.pad_condim
            g.priority = 1
            tactile_sites.append(sname)
            tactile_bodies[sname] = b.name
        # ---- actuators: arm (chain order) then hand
        arm_joint_names = [p + j.name for j in arm.joints]
        M = k.joint_space_inertia(home_arm[side])
        arm_acts = []
        for i, j in enumerate(arm.joints):
            kp, kv, d = servo_gains(j.effort, j.velocity, float(M[i, i]), arm.servo_error_at_full_effort)
            _position_actuator(spec, p + j.name, p + j.name, j.range, j.effort, kp, kv)
            _add_motor_damping(spec, p + j.name, d)
            arm_acts.append(p + j.name)
            ctrl.append(float(home_arm[side][i]))
        hand_acts = []
        for a in (hand.actuators if real is None else ()):
            j = hand.joint(a.joint)
            kp0, kv0, d = servo_gains(a.effort, a.velocity, _finger_inertia(hand, a.joint), hand.servo_error_at_full_effort)
            _position_actuator(spec, p + a.name, p + a.joint, j.range, a.effort,
                               a.kp if a.kp is not None else kp0, a.kv if a.kv is not None else kv0)
            _add_motor_damping(spec, p + a.joint, d)
            hand_acts.append(p + a.name)
            ctrl.append(hand_q[a.joint])
        if real is not None:       # the model's own servos (and tendons for its couplings)
            hand_acts = add_real_actuators(spec, real)
            ctrl += [side_q[a.joint] for a in hand.actuators]
        for c in (hand.couplings if real is None else ()):
            eq = spec.add_equality(name=f"{p}{c.joint}_coupling", type=mujoco.mjtEq.mjEQ_JOINT,
                                   name1=p + c.joint, name2=p + c.master)
            data = np.zeros(len(eq.data))
            data[:5] = c.polycoef
            eq.data = data
        hand_joint_names = [p + j.name for link in links for j in link.joints]
        actuators += arm_acts + hand_acts
        joints += arm_joint_names + hand_joint_names
        qpos += list(home_arm[side]) + [side_q[j.name] for link in links for j in link.joints]
        sides[side] = SideLayout(
            side=side, arm_joints=arm_joint_names, hand_joints=hand_joint_names, arm_actuators=arm_acts,
            hand_actuators=hand_acts, wrist_site=f"{p}wrist_site", tactile_sites=tactile_sites,
            tactile_bodies=tactile_bodies,
            hand_bodies=[b.name for b in bodies.values()] + (real.model_bodies if real is not None else []),
            arm_bodies=arm_bodies, hand_base=palm.name, camera=f"{side}_wrist",
        )
        # the hand base is rigidly on the last arm link: the palm and the links hinged on it
        # (finger bases, thumb base, links near the wrist) cannot meaningfully touch the last two arm links
        near = [lk.name for lk in hand.links if np.linalg.norm(hand_poses[lk.name].pos) < WRIST_NEAR_M]
        wrist = [p + n for n in near] + [p + lk.name for lk in links if lk.parent == links[0].name]
        for b in (wrist if real is None else real.wrist_bodies):
            excludes += [(arm_bodies[-1], b), (arm_bodies[-2], b)]
    seen = set()
    for a, b in excludes:
        key = tuple(sorted((a, b)))
        if key not in seen:
            seen.add(key)
            spec.add_exclude(bodyname1=a, bodyname2=b)
    cameras = add_cameras(emb, world, torso, torso_tf, palms)
    log.debug("added %s: %d joints, %d actuators", emb.name, len(joints), len(actuators))
    return RobotLayout(
        embodiment=emb.name, sides=sides, actuator_names=actuators, joint_names=joints,
        home_ctrl=np.array(ctrl), home_qpos=np.array(qpos), cameras=cameras, _kin=kin,
        hand_model="real" if real_hand else "generated",
    )
