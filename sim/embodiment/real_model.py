"""Optional real hand models (MuJoCo Menagerie or any MJCF file) in place of the generated hand.

A hand file may end with a ``real_model:`` block (plain data, see ``shadow.yaml``):

* ``menagerie: <folder>`` + ``files: {right, left}`` (MJCF per side inside that Menagerie folder) and/or
  ``mjcf: {right, left}`` (paths, relative to the hand file);
* ``name_prefix: {right, left}``: the model's side prefix (``rh_``), stripped before the maps below;
* ``root_body``: the model body bolted to the flange (bodies above it, e.g. a forearm, are left out);
* ``mount: {right, left}``: the root body in OUR hand base frame (per side: Menagerie ships a real left
  model, it is used as is, never mirrored);
* ``link_frame``: our link convention (x lateral, y palm normal, z along the finger) in the model's
  finger-body frames;
* ``drop_joints``: model joints our hand does not have (removed: their bodies become rigid at 0);
* ``joints`` (model -> ours), ``actuators`` (model -> ours, with an optional ``ctrl_scale`` when the
  model's control is not our joint angle, e.g. Shadow's J0 tendon = J1 + J2), ``bodies`` (our link ->
  model body: the palm and every tactile / finger-root link).

Where the model file comes from, in order: ``$MENAGERIE_ROOT/<menagerie>/<file>``, the
``mujoco_menagerie`` package (if importable), then the explicit ``mjcf`` path. Nothing is needed
unless the real model is requested: ``hand_model="real"`` to the builder, or ``B2D_HAND_MODEL=real``.

Our names are kept, so layout, home pose, tactile rig, wrist site and scripted operator work
unchanged: every mapped joint and actuator gets ``{side}_{our name}``; each mapped body gets a massless
child "alias" body ``{side}_{our link}`` whose frame follows our link convention (the palm alias is the
hand base itself), and the tactile sites, pads, wrist site and wrist camera go on the aliases. The
model's own geometry, inertia, joint limits, servo gains and tendons are kept.
"""

from __future__ import annotations

import functools
import importlib
import os
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from .frames import Transform, mat_to_quat
from .hand_file import HandDescription, load_hand
from .mirror import side_transform
from .real_model_file import MENAGERIE_ENV, RealActuator, RealModelError, RealModelSpec

# actuator fields copied from the model (the actuators are re-created in our order: ctrl is
# written as one array in layout order)
_ACTUATOR_FIELDS = ("trntype", "dyntype", "gaintype", "biastype", "dynprm", "gainprm", "biasprm", "gear",
                    "ctrlrange", "forcerange", "actrange", "ctrllimited", "forcelimited", "actlimited",
                    "actdim", "actearly", "lengthrange", "group")
_TENDON_FIELDS = ("limited", "range", "stiffness", "springlength", "damping", "frictionloss", "armature",
                  "margin", "solref_limit", "solimp_limit", "solref_friction", "solimp_friction", "width",
                  "rgba", "group", "actfrclimited", "actfrcrange")


# --------------------------------------------------------------------------------------------
# finding the model file
# --------------------------------------------------------------------------------------------

def _require(hand: HandDescription) -> RealModelSpec:
    if hand.real_model is None:
        raise RealModelError(f"{hand.path}: field 'real_model': a real hand model was requested "
                             f"but this hand file has no 'real_model:' block")
    return hand.real_model


def _candidates(rm: RealModelSpec, side: str):
    """(label, loader) pairs in resolution order; a loader returns an MjSpec or None."""
    if rm.menagerie and rm.files:
        root = os.environ.get(MENAGERIE_ENV)
        path = Path(root) / rm.menagerie / rm.files[side] if root else None
        yield (f"${MENAGERIE_ENV}/{rm.menagerie}/{rm.files[side]} "
               f"({path if root else 'MENAGERIE_ROOT not set'})"), \
            (lambda: mujoco.MjSpec.from_file(str(path)) if path and path.is_file() else None)

        def from_package():
            try:
                mm = importlib.import_module("mujoco_menagerie")
            except ImportError:
                return None
            return mm.get(rm.menagerie).spec(Path(rm.files[side]).stem)

        yield f"the mujoco_menagerie package ({rm.menagerie}, entry {Path(rm.files[side]).stem})", from_package
    if rm.mjcf:
        p = rm.mjcf[side]
        yield f"mjcf path {p}", (lambda: mujoco.MjSpec.from_file(str(p)) if p.is_file() else None)


def load_model_spec(hand: HandDescription, side: str) -> mujoco.MjSpec:
    """A fresh MjSpec of the real model for ``side`` (fresh: attaching consumes it)."""
    rm = _require(hand)
    tried = []
    for label, loader in _candidates(rm, side):
        spec = loader()
        if spec is not None:
            return spec
        tried.append(label)
    raise RealModelError(f"{rm.path}: field 'real_model': the {side} real model of hand {hand.name!r} was not "
                         f"found; searched: " + "; ".join(tried))


# --------------------------------------------------------------------------------------------
# attaching
# --------------------------------------------------------------------------------------------

@functools.lru_cache(maxsize=None)
def _home_frames(hand_name: str, side: str) -> dict[str, Transform]:
    """Every model body's pose in the root body frame at q = 0 (compiled once per hand and side)."""
    hand = load_hand(hand_name)
    rm = hand.real_model
    model = load_model_spec(hand, side).compile()
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    root = model.body(rm.name_prefix[side] + rm.root_body).id
    T_root = Transform(data.xpos[root].copy(), data.xmat[root].reshape(3, 3).copy())
    inv = T_root.inverse()
    return {model.body(i).name: inv @ Transform(data.xpos[i].copy(), data.xmat[i].reshape(3, 3).copy())
            for i in range(1, model.nbody)}


def _subtree(body: mujoco.MjsBody) -> list[mujoco.MjsBody]:
    out = [body]
    for child in body.bodies:
        out += _subtree(child)
    return out


@dataclass
class AttachedHand:
    """The real hand of one side, attached to the arm's last link."""

    bodies: dict[str, mujoco.MjsBody]      # our link -> alias body
    model_bodies: list[str]                # attached model bodies (with geometry)
    wrist_bodies: list[str]                # root body and its children: rigid on the flange
    joint_range: dict[str, tuple[float, float]]   # our joint -> range (radians)
    actuators: list[dict] = field(default_factory=list)   # our order, fields ready for add_actuator


def attach_real_hand(spec: mujoco.MjSpec, parent: mujoco.MjsBody, hand: HandDescription, side: str,
                     hand_base: Transform, prefix: str) -> AttachedHand:
    """Attach the real model of ``side`` at ``hand_base`` (our hand base in ``parent``'s frame),
    rename it to our names and add the alias bodies. Actuators are returned, not added (see
    ``add_real_actuators``): ctrl order is arm then hand per side."""
    rm = _require(hand)
    mp = rm.name_prefix[side]
    child = load_model_spec(hand, side)
    for j in rm.drop_joints:
        if child.joint(mp + j) is None:
            raise RealModelError(f"{rm.path}: field 'real_model.drop_joints': the model has no joint {mp + j!r}")
    # the model's actuators: recorded per our actuator, then removed from the child
    by_model = {a.model: a for a in rm.actuators}
    recorded = {}
    for act in list(child.actuators):
        key = act.name[len(mp):] if act.name.startswith(mp) else act.name
        if key not in by_model:
            target = act.target[len(mp):] if act.target.startswith(mp) else act.target
            if target not in rm.drop_joints:
                raise RealModelError(f"{rm.path}: field 'real_model.actuators': model actuator {act.name!r} "
                                     f"is neither mapped nor on a dropped joint")
        else:
            recorded[by_model[key].name] = (by_model[key], {f: np.copy(getattr(act, f)) if isinstance(
                getattr(act, f), np.ndarray) else getattr(act, f) for f in _ACTUATOR_FIELDS}, act.target)
        child.delete(act)
    missing = [a.model for a in rm.actuators if a.name not in recorded]
    if missing:
        raise RealModelError(f"{rm.path}: field 'real_model.actuators': the model has no actuators {missing}")
    for j in rm.drop_joints:
        child.delete(child.joint(mp + j))
    root = child.body(mp + rm.root_body)
    if root is None:
        raise RealModelError(f"{rm.path}: field 'real_model.root_body': the model has no body {mp + rm.root_body!r}")
    # the mount places the root body itself: drop its pose in the model (e.g. on a forearm)
    root.pos = [0.0, 0.0, 0.0]
    root.quat = [1.0, 0.0, 0.0, 0.0]
    unit = 180.0 / np.pi if child.compiler.degree else 1.0
    ranges = {}
    for j in root.find_all(mujoco.mjtObj.mjOBJ_JOINT):
        key = j.name[len(mp):]
        if key not in rm.joints:
            raise RealModelError(f"{rm.path}: field 'real_model.joints': model joint {j.name!r} is neither "
                                 f"mapped nor dropped")
        ranges[rm.joints[key]] = (float(j.range[0]) / unit, float(j.range[1]) / unit)
    # the scene's physics options win; aligning the child's first keeps attach from warning about them
    for opt in dir(spec.option):
        if not opt.startswith("_"):
            setattr(child.option, opt, getattr(spec.option, opt))
    mount = rm.mount[side]
    T = hand_base @ mount
    frame = parent.add_frame(pos=T.pos, quat=mat_to_quat(T.rot))
    attach_prefix = f"{prefix}{hand.name}_"
    attached_root = frame.attach_body(root, attach_prefix, "")
    model_bodies = _subtree(attached_root)
    for b in model_bodies:
        b.gravcomp = 1.0     # like the generated hand: real hand controllers compensate gravity
    renamed = {attach_prefix + mp + key: prefix + ours for key, ours in rm.joints.items()}
    # tendons name their joints and a wrap cannot be re-pointed: fixed tendons of this hand are
    # recorded, deleted and rebuilt over the renamed joints with the same fields
    tendons = []
    for tendon in [t for t in spec.tendons if t.name.startswith(attach_prefix)]:
        wraps = list(tendon.path)
        if not all(w.type == mujoco.mjtWrap.mjWRAP_JOINT for w in wraps):
            raise RealModelError(f"{rm.path}: field 'real_model': tendon {tendon.name!r} has spatial wraps; "
                                 f"only fixed (joint) tendons are supported")
        tendons.append((tendon.name, {f: np.copy(getattr(tendon, f)) for f in _TENDON_FIELDS},
                        [(w.target.name, float(w.coef)) for w in wraps]))
        spec.delete(tendon)
    for old, new in renamed.items():
        spec.joint(old).name = new
    for name, fields, path in tendons:
        tendon = spec.add_tendon(name=name)
        for f, v in fields.items():
            setattr(tendon, f, v)
        for target, coef in path:
            tendon.wrap_joint(renamed.get(target, target), coef)
    for eq in spec.equalities:
        for end in ("name1", "name2"):
            if getattr(eq, end) in renamed:
                setattr(eq, end, renamed[getattr(eq, end)])
    # alias bodies: our link frames on the model's bodies (left: the mirror of the right one)
    frames = {s: _home_frames(hand.name, s) for s in ("right", side)}
    aliases = {}
    palm = hand.links[0].name
    for link, mbody in rm.bodies.items():
        body = spec.body(attach_prefix + mp + mbody)
        if body is None:
            raise RealModelError(f"{rm.path}: field 'real_model.bodies.{link}': the model has no body {mp + mbody!r}")
        if link == palm:        # the palm's frame is the hand base itself
            pose = mount.inverse()
        else:
            right = rm.mount["right"] @ frames["right"][rm.name_prefix["right"] + mbody] @ rm.link_frame
            pose = (mount @ frames[side][mp + mbody]).inverse() @ side_transform(right, side)
        aliases[link] = body.add_body(name=prefix + link, pos=pose.pos, quat=mat_to_quat(pose.rot))
    actuators = []
    for a in hand.actuators:
        ra, fields, target = recorded[a.name]
        fields = dict(fields, name=prefix + a.name)
        tname = target[len(mp):] if target.startswith(mp) else target
        fields["target"] = prefix + rm.joints[tname] if tname in rm.joints else attach_prefix + target
        if ra.ctrl_scale != 1.0:
            _scale_ctrl(fields, ra, rm)
        actuators.append(fields)
    return AttachedHand(
        bodies=aliases, model_bodies=[b.name for b in model_bodies],
        wrist_bodies=[attached_root.name] + [b.name for b in attached_root.bodies], joint_range=ranges,
        actuators=actuators,
    )


def _scale_ctrl(fields: dict, ra: RealActuator, rm: RealModelSpec) -> None:
    """Make ctrl (and the actuator length) ``s`` times the model's with the same joint torques: a
    position servo's force kp (ctrl - length) through gear g becomes kp / s^2 through s g."""
    s = ra.ctrl_scale
    if fields["gaintype"] != mujoco.mjtGain.mjGAIN_FIXED or fields["biastype"] != mujoco.mjtBias.mjBIAS_AFFINE:
        raise RealModelError(f"{rm.path}: field 'real_model.actuators.{ra.model}.ctrl_scale': only position "
                             f"servos (fixed gain, affine bias) can be rescaled")
    fields["gear"] = fields["gear"] * s
    fields["ctrlrange"] = fields["ctrlrange"] * s
    fields["forcerange"] = fields["forcerange"] / s
    gain, bias = fields["gainprm"].copy(), fields["biasprm"].copy()
    gain[0] /= s * s
    bias[1:3] /= s * s
    fields["gainprm"], fields["biasprm"] = gain, bias


def add_real_actuators(spec: mujoco.MjSpec, attached: AttachedHand) -> list[str]:
    """Add the recorded model actuators (our names, our order); returns their names."""
    names = []
    for fields in attached.actuators:
        act = spec.add_actuator(name=fields["name"], target=fields["target"])
        for f in _ACTUATOR_FIELDS:
            setattr(act, f, fields[f])
        names.append(fields["name"])
    return names
