"""The tactile registry: a hand file's ``tactile`` block as sites, surface groups and their assets.

::

    tactile:
      grouping: side_specific        # the paper's policy: side_shared | side_specific | per_finger
      normal_convention: inward
      resolution: 240
      groups:                        # one surface asset per group and side
        TH: {assets: {right: RTH, left: LTH}, pad: &TH_pad {center: ..., normal: ..., ...}}
        4F: {assets: {right: R4F, left: L4F}, pad: &4F_pad {...}}
      sites:
        - {name: thumb_tip, finger: thumb, group: TH, attach_body: thumb_distal, pad: *TH_pad}

Policies (paper appendix "Unified Tactile Surface Reconstruction"):

* ``side_shared`` (thumb/4F): one group for the thumb, one for all other fingers; each group's one
  asset serves both hands (``assets.right == assets.left``), so its pad must be symmetric under
  the left/right mirror.
* ``side_specific`` (thumb/4F): the same two groups, a right and a left asset each.
* ``per_finger``: one group per site, a right and a left asset each.

Every site of a group carries the group's pad (write ``pad: *anchor``): the builder places each
site's pad geom from it (``sim.embodiment``), and one asset can only serve pads that are identical
in their attach-body frames. ``pad_friction`` and ``pad_condim`` belong to the physics
(``sim.embodiment.description``) and are not read here.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from sim.embodiment.mirror import M as MIRROR
from sim.embodiment.mirror import mirror_vec
from tactile.errors import TactileSpecError
from tactile.pads import PadSpec, parse_pad
from tactile.surface import SurfaceMap, reflected_surface_map, surface_map_from_pad

GROUPINGS = ("side_shared", "side_specific", "per_finger")
NORMAL_CONVENTIONS = ("inward", "outward")
SIDES = ("right", "left")
THUMB = "thumb"
SITE_FIELDS = ("name", "finger", "group", "attach_body")
BLOCK_FIELDS = ("grouping", "normal_convention", "resolution", "groups", "sites", "pad_friction", "pad_condim")
GROUP_FIELDS = ("assets", "pad")
SYMMETRY_TOLERANCE_M = 1e-9


@dataclass(frozen=True)
class SiteSpec:
    name: str
    finger: str
    group: str
    attach_body: str


@dataclass(frozen=True)
class SurfaceGroup:
    name: str
    assets: dict[str, str]  # side -> asset name; equal on both sides when the asset is shared
    pad: PadSpec
    sites: tuple[str, ...]  # site names, file order


@dataclass(frozen=True)
class TactileLayout:
    grouping: str
    normal_convention: str
    resolution: int
    groups: dict[str, SurfaceGroup]  # file order
    sites: tuple[SiteSpec, ...]

    def group_of(self, site: str) -> SurfaceGroup:
        for s in self.sites:
            if s.name == site:
                return self.groups[s.group]
        raise KeyError(f"no tactile site '{site}'; sites: {[s.name for s in self.sites]}")

    def asset_of(self, side: str, site: str) -> str:
        """The surface asset a site uses on ``side``, e.g. ``asset_of("left", "index_tip") == "L4F"``."""
        return self.group_of(site).assets[side]

    def site_assets(self) -> dict[str, str]:
        """The registry's site-to-asset map, sites named as in the MuJoCo model (``{side}_{site}``)."""
        return {f"{side}_{s.name}": self.asset_of(side, s.name) for side in SIDES for s in self.sites}


def _string(value, source, field: str) -> str:
    if not isinstance(value, str) or not value:
        raise TactileSpecError(source, field, "a non-empty string", value)
    return value


def _mapping(raw, source, field: str, keys) -> dict:
    if not isinstance(raw, dict):
        raise TactileSpecError(source, field, "a mapping with " + ", ".join(keys), raw)
    unknown = sorted(str(k) for k in set(raw) - set(keys))
    if unknown:
        raise TactileSpecError(source, f"{field}.{unknown[0]}", "one of " + ", ".join(keys), "unknown")
    return raw


def _is_mirror_symmetric(pad: PadSpec) -> bool:
    vectors = [pad.center, pad.normal, pad.axis]
    return all(np.allclose(mirror_vec(v), v, atol=SYMMETRY_TOLERANCE_M, rtol=0) for v in vectors)


def _parse_group(raw, source, field: str) -> tuple[dict[str, str], PadSpec]:
    raw = _mapping(raw, source, field, GROUP_FIELDS)
    assets = _mapping(raw.get("assets"), source, f"{field}.assets", SIDES)
    for side in SIDES:
        _string(assets.get(side), source, f"{field}.assets.{side}")
    pad = parse_pad(raw.get("pad"), source, f"{field}.pad")
    return {side: assets[side] for side in SIDES}, pad


def _parse_sites(entries, groups: dict, source, field: str) -> list[SiteSpec]:
    if not isinstance(entries, list) or not entries:
        raise TactileSpecError(source, field, "a non-empty list of sites", entries)
    sites: list[SiteSpec] = []
    for i, entry in enumerate(entries):
        where = f"{field}[{i}]"
        entry = _mapping(entry, source, where, (*SITE_FIELDS, "pad"))
        site = SiteSpec(*(_string(entry.get(k), source, f"{where}.{k}") for k in SITE_FIELDS))
        if any(s.name == site.name for s in sites):
            raise TactileSpecError(source, f"{where}.name", "a site name unique in the hand", site.name)
        if site.group not in groups:
            raise TactileSpecError(source, f"{where}.group", "one of the groups " + ", ".join(groups), site.group)
        group_pad = groups[site.group][1]
        expected = f"the pad of group '{site.group}' (tactile.groups.{site.group}.pad; write pad: *anchor)"
        if "pad" not in entry or parse_pad(entry["pad"], source, f"{where}.pad") != group_pad:
            raise TactileSpecError(source, f"{where}.pad", expected)
        sites.append(site)
    return sites


def _check_policy(grouping: str, groups: dict[str, SurfaceGroup], sites: list[SiteSpec], source, field: str):
    """The grouping policy's shape: which sites share a group, and whether sides share assets."""
    thumb = {s.name for s in sites if s.finger == THUMB}
    others = {s.name for s in sites if s.finger != THUMB}
    for name, group in groups.items():
        where = f"{field}.groups.{name}"
        members = set(group.sites)
        if not members:
            raise TactileSpecError(source, where, "at least one site (no site names this group)")
        if grouping == "per_finger" and len(members) != 1:
            raise TactileSpecError(source, where, "one site per group under grouping per_finger", sorted(members))
        if grouping != "per_finger" and members not in (thumb, others):
            raise TactileSpecError(
                source, where, f"either the thumb sites {sorted(thumb)} or all other sites {sorted(others)} "
                f"(grouping {grouping}: thumb/4F)", sorted(members))
        right, left = group.assets["right"], group.assets["left"]
        if grouping == "side_shared" and right != left:
            raise TactileSpecError(source, f"{where}.assets", "one asset for both sides (grouping side_shared)",
                                   group.assets)
        if grouping != "side_shared" and right == left:
            raise TactileSpecError(source, f"{where}.assets", f"different right and left assets (grouping {grouping})",
                                   group.assets)
        if grouping == "side_shared" and not _is_mirror_symmetric(group.pad):
            raise TactileSpecError(source, f"{where}.pad", "a pad symmetric under the left/right mirror (x = 0 in "
                                   "center, normal and axis) so that one asset serves both hands")
    owner: dict[str, str] = {}
    for name, group in groups.items():
        for side in SIDES:
            asset = group.assets[side]
            if owner.setdefault(asset, name) != name:
                raise TactileSpecError(source, f"{field}.groups.{name}.assets.{side}",
                                       f"an asset name not used by group '{owner[asset]}'", asset)


def parse_tactile_block(raw, source=None, field: str = "tactile") -> TactileLayout:
    """Validate a hand file's ``tactile`` mapping (``source`` names the file in errors)."""
    raw = _mapping(raw, source, field, BLOCK_FIELDS)
    grouping = raw.get("grouping")
    if grouping not in GROUPINGS:
        raise TactileSpecError(source, f"{field}.grouping", "one of " + ", ".join(GROUPINGS), grouping)
    convention = raw.get("normal_convention")
    if convention not in NORMAL_CONVENTIONS:
        raise TactileSpecError(
            source, f"{field}.normal_convention", "one of " + ", ".join(NORMAL_CONVENTIONS), convention
        )
    resolution = raw.get("resolution")
    if not isinstance(resolution, int) or isinstance(resolution, bool) or resolution < 1:
        raise TactileSpecError(source, f"{field}.resolution", "a positive integer", resolution)
    raw_groups = raw.get("groups")
    if not isinstance(raw_groups, dict) or not raw_groups:
        raise TactileSpecError(source, f"{field}.groups", "a mapping of group name -> {assets, pad}", raw_groups)
    parsed = {str(name): _parse_group(g, source, f"{field}.groups.{name}") for name, g in raw_groups.items()}
    sites = _parse_sites(raw.get("sites"), parsed, source, f"{field}.sites")
    groups = {
        name: SurfaceGroup(name, assets, pad, tuple(s.name for s in sites if s.group == name))
        for name, (assets, pad) in parsed.items()
    }
    _check_policy(grouping, groups, sites, source, field)
    return TactileLayout(grouping, convention, resolution, groups, tuple(sites))


def surface_assets(
    layout: TactileLayout, resolution: int | None = None, contact_meshes: dict[str, trimesh.Trimesh] | None = None
) -> dict[str, SurfaceMap]:
    """One surface map per asset name, on each group pad's grid at ``resolution`` (default the layout's).

    ``contact_meshes[group]`` is the surface the group's right-hand sites make contact with, in their
    attach-body frame (``tactile.rig`` passes the compiled pad geoms); by default the pad sheet of
    ``tactile.pads``. A left asset is the right one reflected by the embodiment's mirror; a shared
    asset is the same object on both sides.
    """
    resolution = layout.resolution if resolution is None else resolution
    assets: dict[str, SurfaceMap] = {}
    for group in layout.groups.values():
        mesh = None if contact_meshes is None else contact_meshes[group.name]
        right_name, left_name = group.assets["right"], group.assets["left"]
        right = surface_map_from_pad(group.pad, resolution, right_name, mesh)
        assets[right_name] = right
        if left_name != right_name:
            assets[left_name] = reflected_surface_map(right, MIRROR, left_name)
    return assets


def load_tactile_layout(path) -> TactileLayout:
    """The ``tactile`` block of one hand file (YAML read safely); errors name the file."""
    from sim.registry import load_yaml  # the catalog's one safe YAML reader

    return parse_tactile_block(load_yaml(path).get("tactile"), path)


@functools.lru_cache(maxsize=None)
def hand_tactile_layout(hand_file: Path) -> TactileLayout:
    """The registry entry of one catalog hand file, parsed once per process."""
    return load_tactile_layout(hand_file)
