"""Arm files (``sim/catalog/arms/<name>.yaml``): a URDF-like serial chain, its flange and home seed.

Each joint has an ``origin`` (xyz + rpy, parent link frame -> joint frame, which is also the child link
frame) and an ``axis`` in the joint frame; ``flange`` is the tool flange in the last link's frame, +z out."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sim.schema.arm import ArmFile, ChainEntry
from sim.schema.robot_parts import Geom

from .catalog_paths import file_names, read_file, resolve
from .fields import _Ctx
from .frames import Transform, frame_transform
from .links import (NO_GEOM_DEFAULTS, NO_JOINT_DEFAULTS, JointSpec, LinkSpec, build_geom, build_inertial, build_joint,
                    contact_excludes)

KEEP_SIGN_MARGIN_RAD = 0.05   # `ik_keep_sign`: the IK keeps the joint this far from zero (a straight elbow)


@dataclass(frozen=True)
class ArmDescription:
    name: str
    display_name: str
    source: str
    approximations: str
    links: tuple[LinkSpec, ...]      # base link first, then one link per joint in chain order
    flange: Transform                # in the last link frame, +z out of the flange
    home_seed: dict[str, np.ndarray]  # side -> elbow-up seed for the home IK
    servo_error_at_full_effort: float
    contact_exclude: tuple[tuple[str, str], ...]
    path: Path
    # radius (m) around the bimanual home wrist pose in which palm-down wrist poses are reached
    # (``reach.home_radius_m``, measured with ``python -m sim.embodiment.reach``)
    reach_m: float
    # joints whose IK solutions keep the sign they have in the home seed (the elbow's branch): a
    # stretched arm would otherwise flip elbow-down and drive its upper arm into the table
    ik_keep_sign: tuple[str, ...] = ()

    @property
    def joints(self) -> list[JointSpec]:
        return [j for link in self.links for j in link.joints]

    @property
    def dof(self) -> int:
        return len(self.joints)


def arm_names() -> list[str]:
    return file_names("arm")


@functools.lru_cache(maxsize=None)
def load_arm(name: str) -> ArmDescription:
    path = resolve("arm", name)
    _, m = read_file(ArmFile, path)
    ctx = _Ctx(path)
    jdefaults = m.joint_defaults or NO_JOINT_DEFAULTS
    gdefaults = m.geom_defaults or NO_GEOM_DEFAULTS
    base_geoms = tuple(build_geom(g, gdefaults) for g in m.base.geoms)
    links = [LinkSpec(name=m.base.link, parent=None, origin=Transform.identity(), joints=(),
                      geoms=base_geoms, inertial=build_inertial(m.base, base_geoms))]
    for i, entry in enumerate(m.chain):
        end = m.chain[i + 1].origin.xyz if i + 1 < len(m.chain) else m.flange.xyz
        geoms = tuple(build_geom(g, gdefaults) for g in _link_geoms(entry, end))
        links.append(LinkSpec(
            name=entry.link.name, parent=links[-1].name, origin=frame_transform(entry.origin),
            joints=(build_joint(entry, jdefaults),), geoms=geoms, inertial=build_inertial(entry.link, geoms),
        ))
    seed = {}
    for side in ("left", "right"):
        angles = getattr(m.home_seed, side)
        if len(angles) != len(m.chain):
            ctx.sub(f"home_seed.{side}").fail(f"expected a list of {len(m.chain)} numbers (one per joint of the "
                                               f"chain), got {len(angles)}")
        seed[side] = np.asarray(angles, dtype=float)
    return ArmDescription(
        name=m.name if m.name is not None else name,
        display_name=m.display_name if m.display_name is not None else name,
        source=m.source, approximations=m.approximations,
        links=tuple(links), flange=frame_transform(m.flange),
        home_seed=seed,
        servo_error_at_full_effort=m.servo_error_at_full_effort,
        contact_exclude=contact_excludes(m.contact_exclude, ctx, {link.name for link in links}),
        path=path,
        reach_m=m.reach.home_radius_m,
        ik_keep_sign=_keep_sign(m.ik_keep_sign or [], ctx, [link.joints[0].name for link in links[1:]], seed),
    )


def _link_geoms(entry: ChainEntry, end) -> list[Geom]:
    """The link's geoms; with ``segment_radius`` (shorthand) first a capsule from this joint to the next
    joint origin (or the flange), ``end``, and last a joint-housing cylinder along the joint axis."""
    link = entry.link
    if link.segment_radius is None:
        return list(link.geoms)
    end = [float(v) for v in (end if end is not None else [0, 0, 0])]
    r = link.segment_radius
    geoms = list(link.geoms)
    if np.linalg.norm(end) > 1e-3 and not link.no_segment:
        geoms.insert(0, Geom(type="capsule", fromto=[0.0, 0.0, 0.0] + end, radius=r))
    ax = np.asarray(entry.axis if entry.axis is not None else [0, 0, 1], float)
    h = link.housing_half_length if link.housing_half_length is not None else r
    geoms.append(Geom(type="cylinder", fromto=[float(v) for v in (*(-ax * h), *(ax * h))], radius=r * 1.08,
                      rgba=link.housing_rgba if link.housing_rgba is not None else [0.3, 0.3, 0.32, 1.0]))
    return geoms


def _keep_sign(names: list[str], ctx: _Ctx, joint_names: list[str], seed: dict[str, np.ndarray]) -> tuple[str, ...]:
    for i, n in enumerate(names):
        c = ctx.sub(f"ik_keep_sign[{i}]")
        if n not in joint_names:
            c.fail(f"{n!r} is not a joint; expected one of {joint_names}")
        if any(abs(seed[s][joint_names.index(n)]) <= KEEP_SIGN_MARGIN_RAD for s in seed):
            c.fail(f"{n!r} is within {KEEP_SIGN_MARGIN_RAD} rad of zero in a home seed: no clear sign to keep")
    return tuple(names)
