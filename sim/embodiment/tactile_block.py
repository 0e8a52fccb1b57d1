"""A hand file's ``tactile`` block: the contact pads and the site/group registry, checked against the hand's
links and fingers and against the paper's grouping policies (format: the comment before ``_TACTILE_FIELDS``).

The block has its own validator rather than a per-file schema: its rules (one site per finger, pads
identical within a group, mirror-symmetric shared pads) look across the block and the hand's links, and the
tactile layer checks blocks on their own with its own error class (``parse_tactile_block``, ``parse_tactile_pad``)."""

from __future__ import annotations

import math
import dataclasses
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .fields import _Ctx, _expected_error, _is_number, _vec
from .mirror import mirror_vec

TACTILE_GROUPINGS = ("side_shared", "side_specific", "per_finger")
TACTILE_NORMAL_CONVENTIONS = ("inward", "outward")
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

_TACTILE_FIELDS = ("grouping", "normal_convention", "resolution", "groups", "sites", "pad_friction", "pad_condim")
_TACTILE_GROUP_FIELDS = ("assets", "pad")
_TACTILE_SITE_FIELDS = ("name", "finger", "group", "attach_body")
PAD_UNIT_TOLERANCE = 1e-3
PAD_ORTHOGONAL_TOLERANCE = 1e-3
PAD_SYMMETRY_TOLERANCE_M = 1e-9
DEFAULT_PAD_FRICTION = (1.2, 0.02, 0.002)
DEFAULT_PAD_CONDIM = 4
PAD_CONDIMS = (1, 3, 4, 6)


def _string(value, ctx: _Ctx) -> str:
    if not isinstance(value, str) or not value:
        ctx.expect("a non-empty string", value)
    return value


def _mapping(raw, ctx: _Ctx, keys) -> dict:
    if not isinstance(raw, dict):
        ctx.expect("a mapping with " + ", ".join(keys), raw)
    unknown = sorted(str(k) for k in set(raw) - set(keys))
    if unknown:
        ctx.sub(unknown[0]).expect("one of " + ", ".join(keys), "unknown")
    return raw


def _pad_vector(raw: dict, key: str, ctx: _Ctx) -> np.ndarray:
    value = raw.get(key)
    numbers = isinstance(value, (list, tuple)) and all(_is_number(x) for x in value)   # not "12", not true
    vec = np.asarray(value, dtype=np.float64) if numbers else None
    if vec is None or vec.shape != (3,) or not np.all(np.isfinite(vec)):
        ctx.sub(key).expect("a list of 3 finite numbers", value)
    return vec


def _pad_length(value, ctx: _Ctx, allow_zero: bool = False) -> float:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or value < 0 or (value == 0 and not allow_zero):
        ctx.expect("a number >= 0 (metres)" if allow_zero else "a positive number (metres)", value)
    return float(value)


def _pad(raw, ctx: _Ctx) -> TactilePad:
    if not isinstance(raw, dict):
        ctx.expect("a mapping with " + ", ".join(PAD_FIELDS), raw)
    missing = [k for k in PAD_FIELDS if k not in raw and k != "curvature_radius"]
    if missing:
        ctx.sub(missing[0]).expect("a value (field is missing)")
    _mapping(raw, ctx, PAD_FIELDS)
    center, normal, axis = (_pad_vector(raw, k, ctx) for k in ("center", "normal", "axis"))
    for key, vec in (("normal", normal), ("axis", axis)):
        if abs(np.linalg.norm(vec) - 1.0) > PAD_UNIT_TOLERANCE:
            ctx.sub(key).expect("a unit vector", vec.tolist())
    if abs(float(normal @ axis)) > PAD_ORTHOGONAL_TOLERANCE:
        ctx.sub("axis").expect("a vector orthogonal to normal", axis.tolist())
    normal = normal / np.linalg.norm(normal)
    axis = axis - (axis @ normal) * normal
    return TactilePad(
        center=center, normal=normal, axis=axis / np.linalg.norm(axis),
        length=_pad_length(raw.get("length"), ctx.sub("length")),
        width=_pad_length(raw.get("width"), ctx.sub("width")),
        curvature_radius=_pad_length(raw.get("curvature_radius", 0.0), ctx.sub("curvature_radius"), True),
    )


def parse_tactile_pad(raw, source=None, field: str = "pad", error: Callable = _expected_error) -> TactilePad:
    """Validate one ``pad`` mapping; errors (built by ``error``) name ``source`` and the dotted field path."""
    return _pad(raw, _Ctx(source, field, error))


def _pad_is_mirror_symmetric(pad: TactilePad) -> bool:
    return all(np.allclose(mirror_vec(v), v, atol=PAD_SYMMETRY_TOLERANCE_M, rtol=0)
               for v in (pad.center, pad.normal, pad.axis))


def _tactile_sites(entries, pads: dict[str, TactilePad], ctx: _Ctx, link_names: set[str],
                   fingers: list[str]) -> list[TactileSite]:
    if not isinstance(entries, list) or not entries:
        ctx.sub("sites").expect("a non-empty list of sites", entries)
    sites: list[TactileSite] = []
    for i, entry in enumerate(entries):
        sctx = ctx.sub(f"sites[{i}]")
        entry = _mapping(entry, sctx, (*_TACTILE_SITE_FIELDS, "pad"))
        name, finger, group, body = (_string(entry.get(k), sctx.sub(k)) for k in _TACTILE_SITE_FIELDS)
        if any(s.name == name for s in sites):
            sctx.sub("name").expect("a site name unique in the hand", name)
        if finger not in fingers:
            sctx.sub("finger").expect("one of the fingers " + ", ".join(fingers), finger)
        if body not in link_names:
            sctx.sub("attach_body").expect("a link of this hand", body)
        if group not in pads:
            sctx.sub("group").expect("one of the groups " + ", ".join(pads), group)
        expected = f"the pad of group '{group}' (tactile.groups.{group}.pad; write pad: *anchor)"
        if "pad" not in entry or not _pad(entry["pad"], sctx.sub("pad")).same_as(pads[group]):
            sctx.sub("pad").expect(expected)
        sites.append(TactileSite(name, finger, group, body, pads[group]))
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


def _tactile_block(raw, ctx: _Ctx, link_names: set[str], fingers: list[str]) -> TactileSpec:
    raw = _mapping(raw, ctx, _TACTILE_FIELDS)
    grouping = raw.get("grouping")
    if grouping not in TACTILE_GROUPINGS:
        ctx.sub("grouping").expect("one of " + ", ".join(TACTILE_GROUPINGS), grouping)
    convention = raw.get("normal_convention")
    if convention not in TACTILE_NORMAL_CONVENTIONS:
        ctx.sub("normal_convention").expect("one of " + ", ".join(TACTILE_NORMAL_CONVENTIONS), convention)
    resolution = raw.get("resolution")
    if not isinstance(resolution, int) or isinstance(resolution, bool) or resolution < 1:
        ctx.sub("resolution").expect("a positive integer", resolution)
    friction = _vec(raw.get("pad_friction", DEFAULT_PAD_FRICTION), 3, ctx.sub("pad_friction"))
    condim = raw.get("pad_condim", DEFAULT_PAD_CONDIM)
    if condim not in PAD_CONDIMS or isinstance(condim, bool):
        ctx.sub("pad_condim").expect("one of " + ", ".join(map(str, PAD_CONDIMS)), condim)
    raw_groups = raw.get("groups")
    if not isinstance(raw_groups, dict) or not raw_groups:
        ctx.sub("groups").expect("a mapping of group name -> {assets, pad}", raw_groups)
    assets, pads = {}, {}
    for name, g in raw_groups.items():
        gctx = ctx.sub(f"groups.{name}")
        g = _mapping(g, gctx, _TACTILE_GROUP_FIELDS)
        sides = _mapping(g.get("assets"), gctx.sub("assets"), TACTILE_SIDES)
        assets[str(name)] = {side: _string(sides.get(side), gctx.sub(f"assets.{side}")) for side in TACTILE_SIDES}
        pads[str(name)] = _pad(g.get("pad"), gctx.sub("pad"))
    sites = _tactile_sites(raw.get("sites"), pads, ctx, link_names, fingers)
    groups = {name: TactileGroup(name, assets[name], pads[name], tuple(s.name for s in sites if s.group == name))
              for name in pads}
    _check_tactile_policy(grouping, groups, sites, ctx)
    return TactileSpec(grouping=grouping, normal_convention=convention, resolution=resolution, groups=groups,
                       sites=tuple(sites), pad_friction=tuple(float(x) for x in friction), pad_condim=int(condim))


def parse_tactile_block(raw, source, link_names: set[str], fingers: list[str], field: str = "tactile") -> TactileSpec:
    """Validate a hand's ``tactile`` mapping against its links and fingers (``source`` names the file in errors)."""
    return _tactile_block(raw, _Ctx(source, field), set(link_names), list(fingers))


def hand_tactile(data: dict, ctx: _Ctx, link_names: set[str], fingers: list[str]) -> TactileSpec:
    """The ``tactile`` block of a hand file's raw mapping (the schema has checked it is a mapping)."""
    return _tactile_block(data["tactile"], ctx.sub("tactile"), link_names, fingers)


def side_pad(p: TactilePad, side: str) -> TactilePad:
    """The pad as mounted on ``side``: pads are described for the right hand, mirrored for the left."""
    if side != "left":
        return p
    return dataclasses.replace(p, center=mirror_vec(p.center), normal=mirror_vec(p.normal), axis=mirror_vec(p.axis))
