"""Embodiment files (``sim/catalog/embodiments/<name>.yaml``): an arm file and a hand file, mounted for
both sides, with their home pose, cameras and torso."""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from sim.schema.embodiment import CAMERA_NAMES, EmbodimentFile

from .arm_file import ArmDescription, load_arm
from .catalog_paths import file_names, read_file, resolve
from .fields import _Ctx
from .frames import Transform, frame_transform
from .hand_file import HandDescription, load_hand

DEFAULT_FOVY = {"chest": 70.0, "overhead": 60.0, "stereo_left": 60.0, "stereo_right": 60.0,
                "left_wrist": 80.0, "right_wrist": 80.0}
SIDES = ("left", "right")


@dataclass(frozen=True)
class CameraSpec:
    name: str
    fovy: float
    pos: np.ndarray | None = None
    target: np.ndarray | None = None


@dataclass(frozen=True)
class EmbodimentDescription:
    name: str
    display_name: str
    arm: ArmDescription
    hand: HandDescription
    mounts: dict[str, Transform]            # side -> arm base in world
    home_wrist: Transform                    # right wrist-site home pose in world (left mirrored)
    home_arm: dict[str, np.ndarray] | None   # optional explicit arm home per side
    home_seed: dict[str, np.ndarray] | None  # optional IK seeds per side (else the arm file's)
    torso: dict[str, Any]
    cameras: dict[str, CameraSpec]
    path: Path
    # tactile registry override: site -> hand link whose frame holds the site and its pad (the pad's
    # centre, normal and axis are read in that link's frame); sites not named keep the hand file's body
    tactile_attach: dict[str, str] = field(default_factory=dict)


def embodiment_names() -> list[str]:
    """Names of the embodiment files in ``sim/catalog/embodiments``."""
    return file_names("embodiment")


@functools.lru_cache(maxsize=None)
def load_embodiment(name: str) -> EmbodimentDescription:
    path = resolve("embodiment", name)
    data, m = read_file(EmbodimentFile, path)
    ctx = _Ctx(path)
    arm = load_arm(m.arm)
    hand = load_hand(m.hand)
    clash = ({lk.name for lk in arm.links} & {lk.name for lk in hand.links}) | \
        ({j.name for j in arm.joints} & {j.name for j in hand.joints})
    if clash:
        ctx.fail(f"arm {arm.name!r} and hand {hand.name!r} share link/joint names {sorted(clash)}; "
                 "rename them in the hand file")
    mounts = {side: frame_transform(getattr(m.mount, side)) for side in SIDES}
    home_arm = _per_side(m.home.arm, arm.dof, ctx.sub("home.arm"))
    home_seed = _per_side(m.home.seed, arm.dof, ctx.sub("home.seed"))
    cams = m.cameras or {}
    cameras = {}
    for cname in CAMERA_NAMES:
        c = cams.get(cname)
        cameras[cname] = CameraSpec(
            name=cname, fovy=c.fovy if c is not None and c.fovy is not None else DEFAULT_FOVY[cname],
            pos=np.asarray(c.pos, float) if c is not None and c.pos is not None else None,
            target=np.asarray(c.target, float) if c is not None and c.target is not None else None,
        )
    return EmbodimentDescription(
        name=m.name if m.name is not None else name, display_name=m.display_name,
        arm=arm, hand=hand, mounts=mounts, home_wrist=frame_transform(m.home.right_wrist), home_arm=home_arm,
        home_seed=home_seed, torso=dict(data.get("torso") or {}), cameras=cameras, path=path,
        tactile_attach=_tactile_attach(m.tactile_attach or {}, hand, ctx.sub("tactile_attach")),
    )


def _per_side(vectors, dof: int, ctx: _Ctx) -> dict[str, np.ndarray] | None:
    """``home.arm`` / ``home.seed``: one joint vector per side, as long as the arm's chain."""
    if vectors is None:
        return None
    out = {}
    for side in SIDES:
        v = getattr(vectors, side)
        if len(v) != dof:
            ctx.sub(side).fail(f"expected a list of {dof} numbers (one per arm joint), got {len(v)}")
        out[side] = np.asarray(v, dtype=float)
    return out


def _tactile_attach(raw: dict, hand: HandDescription, ctx: _Ctx) -> dict[str, str]:
    """The embodiment's per-site attach-body overrides, checked against the hand's sites and links."""
    sites = [s.name for s in hand.tactile.sites]
    links = {lk.name for lk in hand.links}
    out = {}
    for site, link in raw.items():
        if site not in sites:
            ctx.sub(str(site)).fail(f"expected a tactile site of hand {hand.name!r} {sites}")
        if link not in links:
            ctx.sub(str(site)).fail(f"expected a link of hand {hand.name!r}, got {link!r}")
        if hand.real_model is not None and link not in hand.real_model.bodies:   # must exist on both hand models
            ctx.sub(str(site)).fail(f"expected a link mapped in hand {hand.name!r}'s real_model.bodies "
                                    f"{sorted(hand.real_model.bodies)}, got {link!r}")
        out[str(site)] = str(link)
    return out
