"""A hand file's ``real_model:`` block (see real_model.py for what it says), read and checked; apart from
the attaching code so that the hand file's reader needs nothing that builds on hands."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from .fields import _Ctx, _get, _num
from .frames import Transform, _transform
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


def _str_map(raw, ctx: _Ctx) -> dict[str, str]:
    if not isinstance(raw, dict) or not raw:
        ctx.fail(f"expected a non-empty mapping, got {raw!r}")
    return {str(k): str(v) for k, v in raw.items()}


def _sides(raw, ctx: _Ctx) -> dict:
    if not isinstance(raw, dict) or set(raw) != set(SIDES):
        ctx.fail(f"expected a mapping with exactly the keys {list(SIDES)}, got {raw!r}")
    return raw


def parse_real_model(raw: dict, ctx: _Ctx, links: list[LinkSpec], fingers: list[str],
                     actuator_names: list[str], tactile_bodies: set[str]) -> RealModelSpec:
    """Validate the ``real_model:`` block against the generated hand it replaces."""
    if not isinstance(raw, dict):
        ctx.fail(f"expected a mapping, got {type(raw).__name__}")
    menagerie = raw.get("menagerie")
    files = {s: str(v) for s, v in _sides(raw["files"], ctx.sub("files")).items()} if "files" in raw else {}
    mjcf = {s: (ctx.path.parent / str(v)).resolve() for s, v in _sides(raw["mjcf"], ctx.sub("mjcf")).items()} \
        if "mjcf" in raw else {}
    if not (menagerie and files) and not mjcf:
        ctx.fail("expected 'menagerie' + 'files: {right, left}' and/or 'mjcf: {right, left}'")
    prefix = {s: str(v) for s, v in _sides(raw.get("name_prefix", {"right": "", "left": ""}),
                                           ctx.sub("name_prefix")).items()}
    mount = {s: _transform(v, ctx.sub(f"mount.{s}"))
             for s, v in _sides(_get(raw, "mount", ctx), ctx.sub("mount")).items()}
    joints = _str_map(_get(raw, "joints", ctx), ctx.sub("joints"))
    ours = {j.name for link in links for j in link.joints}
    mapped = set(joints.values())
    if mapped != ours or len(mapped) != len(joints):
        ctx.sub("joints").fail(f"expected a one-to-one map onto the hand's joints; missing {sorted(ours - mapped)}, "
                               f"unknown {sorted(mapped - ours)}")
    acts = []
    for model_name, v in _get(raw, "actuators", ctx).items():
        actx = ctx.sub(f"actuators.{model_name}")
        if isinstance(v, dict):
            acts.append(RealActuator(str(model_name), str(_get(v, "name", actx)),
                                     _num(v.get("ctrl_scale", 1.0), actx.sub("ctrl_scale"), positive=True)))
        else:
            acts.append(RealActuator(str(model_name), str(v), 1.0))
    got = [a.name for a in acts]
    if sorted(got) != sorted(actuator_names):
        ctx.sub("actuators").fail(f"expected one entry per actuator of the hand {actuator_names}, got {got}")
    bodies = _str_map(_get(raw, "bodies", ctx), ctx.sub("bodies"))
    palm = links[0].name
    roots = {next(lk.name for lk in links if lk.finger == f) for f in fingers}
    needed = {palm} | set(tactile_bodies) | roots
    if not needed <= set(bodies):
        ctx.sub("bodies").fail(f"expected the palm, every tactile attach body and every finger's first link; "
                               f"missing {sorted(needed - set(bodies))}")
    unknown = set(bodies) - {lk.name for lk in links}
    if unknown:
        ctx.sub("bodies").fail(f"{sorted(unknown)} are not links of this hand")
    return RealModelSpec(
        source=str(_get(raw, "source", ctx)), menagerie=str(menagerie) if menagerie else None, files=files,
        mjcf=mjcf, name_prefix=prefix, root_body=str(_get(raw, "root_body", ctx)), mount=mount,
        link_frame=_transform(raw.get("link_frame"), ctx.sub("link_frame")),
        drop_joints=tuple(str(j) for j in raw.get("drop_joints", []) or []), joints=joints,
        actuators=tuple(acts), bodies=bodies, path=ctx.path,
    )
