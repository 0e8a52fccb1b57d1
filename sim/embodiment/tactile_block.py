"""A hand file's ``tactile`` block: the contact pads and the site/group registry, checked against the hand's
links and fingers and against the paper's grouping policies (format: the comment before ``_TACTILE_FIELDS``).

Keys, types, ranges and each pad on its own are checked by the block's schema (sim/schema/tactile.py); this
module checks what looks across the block and the hand's links (one site per finger, pads identical within
a group, mirror-symmetric shared pads), and the tactile layer checks blocks on their own with its own error
class (``parse_tactile_block``, ``parse_tactile_pad``)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable

import numpy as np

from sim.schema import validate
from sim.schema.tactile import Pad, TactileBlock

from .fields import _Ctx, _expected_error
from .mirror import mirror_vec

TACTILE_SIDES = ("right", "left")
THUMB = "thumb"
PAD_FIELDS = ("center", "normal", "axis", "length", "width", "curvature_radius")


@dataclass(frozen=True, eq=False)  # arrays: compare pads with same_as
class TactilePad:
    """A contact pad in its attach-body frame (metres); ``tactile.pads`` meshes its surface.

    Pad frame: origin ``center``; ``e_width = axis x normal``, ``e_axis = axis``, ``e_normal = normal``
    (right-handed). The surface is the sheet ``h(x)`` over ``|x| <= width/2`` (x along e_width),
    straight along the axis. With radius R > 0: ``a = max(0, width/2 - R)``, ``t = max(0, |x| - a)``,
    ``h = sqrt(R^2 - t^2) - R``: a circular arc for R >= width/2, a flat middle with rounded edges of
    radius R otherwise.
    """

    center: np.ndarray   # on the contact surface
    normal: np.ndarray   # unit, outward (towards objects)
    axis: np.ndarray     # unit, along the finger, orthogonal to normal
    length: float        # along axis
    width: float         # across axis
    curvature_radius: float = 0.0  # cylindrical rounding across the width; 0 = flat

    def frame(self) -> np.ndarray:
        """3x3 rotation whose columns are e_width, e_axis, e_normal (attach-body frame)."""
        n = np.asarray(self.normal, dtype=np.float64)
        a = np.asarray(self.axis, dtype=np.float64)
        return np.column_stack([np.cross(a, n), a, n])

    def profile(self, x: np.ndarray) -> np.ndarray:
        """Surface height h(x) <= 0 below the centre plane, x across the width (metres)."""
        r = self.curvature_radius
        if r == 0:
            return np.zeros_like(x, dtype=np.float64)
        t = np.maximum(0.0, np.abs(x) - max(0.0, self.width / 2 - r))
        return np.sqrt(np.maximum(r * r - t * t, 0.0)) - r

    def same_as(self, other: "TactilePad") -> bool:
        return all(np.array_equal(getattr(self, k), getattr(other, k)) for k in PAD_FIELDS)


@dataclass(frozen=True)
class TactileSite:
    name: str
    finger: str
    group: str           # surface group, e.g. "4F"
    attach_body: str
    pad: TactilePad      # the group's pad


@dataclass(frozen=True)
class TactileGroup:
    """Sites that share one surface asset per side (all carry the group's pad)."""

    name: str
    assets: dict[str, str]   # side -> asset name; equal on both sides when the asset is shared
    pad: TactilePad
    sites: tuple[str, ...]   # site names, file order


@dataclass(frozen=True)
class TactileSpec:
    """A hand file's ``tactile`` block (format: the comment before ``_TACTILE_FIELDS``): physics pads and registry."""

    grouping: str
    normal_convention: str
    resolution: int
    groups: dict[str, TactileGroup]   # file order
    sites: tuple[TactileSite, ...]
    pad_friction: tuple[float, float, float]
    pad_condim: int

    def group_of(self, site: str) -> TactileGroup:
        for s in self.sites:
            if s.name == site:
                return self.groups[s.group]
        raise KeyError(f"no tactile site '{site}'; sites: {[s.name for s in self.sites]}")

    def asset_of(self, side: str, site: str) -> str:
        """The surface asset a site uses on ``side``, e.g. ``asset_of("left", "index_tip") == "L4F"``."""
        return self.group_of(site).assets[side]

    def site_assets(self) -> dict[str, str]:
        """The site-to-asset map, sites named as in the MuJoCo model (``{side}_{site}``)."""
        return {f"{side}_{s.name}": self.asset_of(side, s.name) for side in TACTILE_SIDES for s in self.sites}


#       pad_friction: [1.2, 0.02, 0.002]   # optional, the pad geoms' friction and condim
#       pad_condim: 4
#       groups:                        # one surface asset per group and side
#         TH: {assets: {right: RTH, left: LTH}, pad: &TH_pad {center: ..., normal: ..., ...}}
#         4F: {assets: {right: R4F, left: L4F}, pad: &4F_pad {...}}
#       sites:                         # one per finger
#         - {name: thumb_tip, finger: thumb, group: TH, attach_body: thumb_distal, pad: *TH_pad}
#
# Policies (paper appendix "Unified Tactile Surface Reconstruction"): ``side_shared`` (thumb/4F): one
# group for the thumb, one for all other fingers, each group's one asset serving both hands
# (``assets.right == assets.left``), so its pad must be symmetric under the left/right mirror;
# ``side_specific`` (thumb/4F): the same two groups, a right and a left asset each; ``per_finger``:
# one group per site, a right and a left asset each. Every site of a group carries the group's pad
# (write ``pad: *anchor``): the builder places each site's pad geom from it, and one asset can only
# serve pads that are identical in their attach-body frames.

PAD_SYMMETRY_TOLERANCE_M = 1e-9


def _pad(pad: Pad) -> TactilePad:
    """A checked pad, its normal and axis made exactly unit and orthogonal."""
    normal = np.asarray(pad.normal, dtype=np.float64)
    axis = np.asarray(pad.axis, dtype=np.float64)
    normal = normal / np.linalg.norm(normal)
    axis = axis - (axis @ normal) * normal
    return TactilePad(center=np.asarray(pad.center, dtype=np.float64), normal=normal, axis=axis / np.linalg.norm(axis),
                      length=float(pad.length), width=float(pad.width), curvature_radius=float(pad.curvature_radius))


def parse_tactile_pad(raw, source=None, field: str = "pad", error: Callable = _expected_error) -> TactilePad:
    """Validate one ``pad`` mapping; errors (built by ``error``) name ``source`` and the dotted field path."""
    return _pad(validate(Pad, raw, source, prefix=field, error=error))


def _pad_is_mirror_symmetric(pad: TactilePad) -> bool:
    return all(np.allclose(mirror_vec(v), v, atol=PAD_SYMMETRY_TOLERANCE_M, rtol=0)
               for v in (pad.center, pad.normal, pad.axis))


def _tactile_sites(block: TactileBlock, pads: dict[str, TactilePad], ctx: _Ctx, link_names: set[str],
                   fingers: list[str]) -> list[TactileSite]:
    sites: list[TactileSite] = []
    for i, entry in enumerate(block.sites):
        sctx = ctx.sub(f"sites[{i}]")
        if any(s.name == entry.name for s in sites):
            sctx.sub("name").expect("a site name unique in the hand", entry.name)
        if entry.finger not in fingers:
            sctx.sub("finger").expect("one of the fingers " + ", ".join(fingers), entry.finger)
        if entry.attach_body not in link_names:
            sctx.sub("attach_body").expect("a link of this hand", entry.attach_body)
        if entry.group not in pads:
            sctx.sub("group").expect("one of the groups " + ", ".join(pads), entry.group)
        expected = f"the pad of group '{entry.group}' (tactile.groups.{entry.group}.pad; write pad: *anchor)"
        if entry.pad is None or not _pad(entry.pad).same_as(pads[entry.group]):
            sctx.sub("pad").expect(expected)
        sites.append(TactileSite(entry.name, entry.finger, entry.group, entry.attach_body, pads[entry.group]))
    covered = {s.finger for s in sites}
    if covered != set(fingers):
        ctx.sub("sites").expect(f"one site per finger {fingers}", sorted(covered))
    return sites


def _check_tactile_policy(grouping: str, groups: dict[str, TactileGroup], sites: list[TactileSite], ctx: _Ctx):
    """The grouping policy's shape: which sites share a group, and whether sides share assets."""
    thumb = {s.name for s in sites if s.finger == THUMB}
    others = {s.name for s in sites if s.finger != THUMB}
    for name, group in groups.items():
        gctx = ctx.sub(f"groups.{name}")
        members = set(group.sites)
        if not members:
            gctx.expect("at least one site (no site names this group)")
        if grouping == "per_finger" and len(members) != 1:
            gctx.expect("one site per group under grouping per_finger", sorted(members))
        if grouping != "per_finger" and members not in (thumb, others):
            gctx.expect(f"either the thumb sites {sorted(thumb)} or all other sites {sorted(others)} "
                        f"(grouping {grouping}: thumb/4F)", sorted(members))
        right, left = group.assets["right"], group.assets["left"]
        if grouping == "side_shared" and right != left:
            gctx.sub("assets").expect("one asset for both sides (grouping side_shared)", group.assets)
        if grouping != "side_shared" and right == left:
            gctx.sub("assets").expect(f"different right and left assets (grouping {grouping})", group.assets)
        if grouping == "side_shared" and not _pad_is_mirror_symmetric(group.pad):
            gctx.sub("pad").expect("a pad symmetric under the left/right mirror (x = 0 in center, normal and "
                                   "axis) so that one asset serves both hands")
    owner: dict[str, str] = {}
    for name, group in groups.items():
        for side in TACTILE_SIDES:
            asset = group.assets[side]
            if owner.setdefault(asset, name) != name:
                ctx.sub(f"groups.{name}.assets.{side}").expect(f"an asset name not used by group '{owner[asset]}'",
                                                               asset)


def _tactile_block(block: TactileBlock, ctx: _Ctx, link_names: set[str], fingers: list[str]) -> TactileSpec:
    pads = {name: _pad(group.pad) for name, group in block.groups.items()}
    sites = _tactile_sites(block, pads, ctx, link_names, fingers)
    groups = {name: TactileGroup(name, {side: getattr(block.groups[name].assets, side) for side in TACTILE_SIDES},
                                 pads[name], tuple(s.name for s in sites if s.group == name))
              for name in pads}
    _check_tactile_policy(block.grouping, groups, sites, ctx)
    return TactileSpec(grouping=block.grouping, normal_convention=block.normal_convention,
                       resolution=block.resolution, groups=groups, sites=tuple(sites),
                       pad_friction=tuple(float(x) for x in block.pad_friction), pad_condim=int(block.pad_condim))


def parse_tactile_block(raw, source, link_names: set[str], fingers: list[str], field: str = "tactile") -> TactileSpec:
    """Validate a hand's ``tactile`` mapping against its links and fingers (``source`` names the file in errors)."""
    ctx = _Ctx(source, field)
    block = validate(TactileBlock, raw, source, prefix=field, error=ctx.error)
    return _tactile_block(block, ctx, set(link_names), list(fingers))


def hand_tactile(block: TactileBlock, ctx: _Ctx, link_names: set[str], fingers: list[str]) -> TactileSpec:
    """A hand file's ``tactile`` block, checked by the hand's schema, checked against its links and fingers."""
    return _tactile_block(block, ctx, link_names, fingers)


def side_pad(p: TactilePad, side: str) -> TactilePad:
    """The pad as mounted on ``side``: pads are described for the right hand, mirrored for the left."""
    if side != "left":
        return p
    return dataclasses.replace(p, center=mirror_vec(p.center), normal=mirror_vec(p.normal), axis=mirror_vec(p.axis))
