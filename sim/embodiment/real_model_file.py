"""A hand file's ``real_model:`` block (see real_model.py for what it says), read and checked; apart from
the attaching code so that the hand file's reader needs nothing that builds on hands."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from sim.schema.real_model import RealModel

from .fields import _Ctx
from .frames import Transform, frame_transform
from .links import LinkSpec

HAND_MODELS = ("generated", "real")
HAND_MODEL_ENV = "B2D_HAND_MODEL"
MENAGERIE_ENV = "MENAGERIE_ROOT"
SIDES = ("left", "right")


class RealModelError(ValueError):
    """The real model was requested but cannot be found or does not match the hand file."""


def requested_hand_model(hand_model: str | None) -> str:
    """``hand_model`` if given, else ``$B2D_HAND_MODEL``, else ``"generated"``."""
    value = hand_model if hand_model is not None else os.environ.get(HAND_MODEL_ENV, "generated")
    if value not in HAND_MODELS:
        src = "hand_model" if hand_model is not None else f"${HAND_MODEL_ENV}"
        raise RealModelError(f"{src}: expected one of {HAND_MODELS}, got {value!r}")
    return value


@dataclass(frozen=True)
class RealActuator:
    model: str          # model actuator name (side prefix stripped)
    name: str           # our actuator name
    ctrl_scale: float   # our ctrl = ctrl_scale * the model's ctrl


@dataclass(frozen=True)
class RealModelSpec:
    source: str
    menagerie: str | None
    files: dict[str, str]
    mjcf: dict[str, Path]
    name_prefix: dict[str, str]
    root_body: str
    mount: dict[str, Transform]
    link_frame: Transform
    drop_joints: tuple[str, ...]
    joints: dict[str, str]            # model joint -> our joint
    actuators: tuple[RealActuator, ...]
    bodies: dict[str, str]            # our link -> model body
    path: Path                        # the hand file


def parse_real_model(m: RealModel, ctx: _Ctx, links: list[LinkSpec], fingers: list[str],
                     actuator_names: list[str], tactile_bodies: set[str]) -> RealModelSpec:
    """The ``real_model:`` block (checked by its schema, sim/schema/real_model.py), checked against the
    generated hand it replaces."""
    ours = {j.name for link in links for j in link.joints}
    mapped = set(m.joints.values())
    if mapped != ours or len(mapped) != len(m.joints):
        ctx.sub("joints").fail(f"expected a one-to-one map onto the hand's joints; missing {sorted(ours - mapped)}, "
                               f"unknown {sorted(mapped - ours)}")
    acts = tuple(RealActuator(model_name, a.name, a.ctrl_scale) for model_name, a in m.actuators.items())
    got = [a.name for a in acts]
    if sorted(got) != sorted(actuator_names):
        ctx.sub("actuators").fail(f"expected one entry per actuator of the hand {actuator_names}, got {got}")
    palm = links[0].name
    roots = {next(lk.name for lk in links if lk.finger == f) for f in fingers}
    needed = {palm} | set(tactile_bodies) | roots
    if not needed <= set(m.bodies):
        ctx.sub("bodies").fail(f"expected the palm, every tactile attach body and every finger's first link; "
                               f"missing {sorted(needed - set(m.bodies))}")
    unknown = set(m.bodies) - {lk.name for lk in links}
    if unknown:
        ctx.sub("bodies").fail(f"{sorted(unknown)} are not links of this hand")

    return RealModelSpec(
        source=m.source, menagerie=m.menagerie, files=dict(m.files) if m.files else {},
        mjcf={s: (ctx.path.parent / v).resolve() for s, v in m.mjcf} if m.mjcf else {},
        name_prefix=dict(m.name_prefix) if m.name_prefix else {s: "" for s in SIDES}, root_body=m.root_body,
        mount={s: frame_transform(frame) for s, frame in m.mount}, link_frame=frame_transform(m.link_frame),
        drop_joints=tuple(m.drop_joints),
        joints=dict(m.joints), actuators=acts, bodies=dict(m.bodies), path=ctx.path,
    )
