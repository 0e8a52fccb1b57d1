"""The tactile block of a hand file: grouping, normal convention, resolution and sites.

::

    tactile:
      grouping: side_shared | side_specific | per_finger
      normal_convention: inward | outward
      resolution: 240
      sites:
        - {name: rh_index, finger: index, group: R4F, attach_body: rh_ffdistal, pad: {...}}

Sites sharing a ``group`` share one surface asset, so their pads (each in its own attach-body
frame) must agree; a site may omit ``pad`` when another site of its group carries it.
"""

from __future__ import annotations

from dataclasses import dataclass

from tactile.errors import TactileSpecError
from tactile.pads import PadSpec, parse_pad
from tactile.sensor import TactileSite
from tactile.surface import SurfaceMap, surface_map_from_pad

GROUPINGS = ("side_shared", "side_specific", "per_finger")
NORMAL_CONVENTIONS = ("inward", "outward")
SITE_FIELDS = ("name", "finger", "group", "attach_body")


@dataclass(frozen=True)
class SiteSpec:
    name: str
    finger: str
    group: str
    attach_body: str


@dataclass(frozen=True)
class TactileLayout:
    grouping: str
    normal_convention: str
    resolution: int
    sites: tuple[SiteSpec, ...]
    pads: dict[str, PadSpec]  # group -> pad

    @property
    def groups(self) -> list[str]:
        return list(self.pads)


def parse_tactile_block(raw, source=None, field: str = "tactile") -> TactileLayout:
    """Validate a hand file's ``tactile`` mapping (``source`` names the file in errors)."""
    if not isinstance(raw, dict):
        raise TactileSpecError(source, field, "a mapping with grouping, normal_convention, resolution, sites", raw)
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
    entries = raw.get("sites")
    if not isinstance(entries, list) or not entries:
        raise TactileSpecError(source, f"{field}.sites", "a non-empty list of sites", entries)

    sites: list[SiteSpec] = []
    pads: dict[str, PadSpec] = {}
    pad_owner: dict[str, str] = {}
    for i, entry in enumerate(entries):
        where = f"{field}.sites[{i}]"
        if not isinstance(entry, dict):
            raise TactileSpecError(source, where, "a mapping with " + ", ".join(SITE_FIELDS), entry)
        for key in SITE_FIELDS:
            if not isinstance(entry.get(key), str) or not entry[key]:
                raise TactileSpecError(source, f"{where}.{key}", "a non-empty string", entry.get(key))
        site = SiteSpec(*(entry[k] for k in SITE_FIELDS))
        if any(s.name == site.name for s in sites):
            raise TactileSpecError(source, f"{where}.name", "a site name unique in the hand", site.name)
        if "pad" in entry:
            pad = parse_pad(entry["pad"], source, f"{where}.pad")
            if site.group in pads and pads[site.group] != pad:
                raise TactileSpecError(
                    source, f"{where}.pad",
                    f"the same pad as site '{pad_owner[site.group]}' (both in group '{site.group}')",
                )
            pads.setdefault(site.group, pad)
            pad_owner.setdefault(site.group, site.name)
        sites.append(site)
    for i, site in enumerate(sites):
        if site.group not in pads:
            raise TactileSpecError(
                source, f"{field}.sites[{i}].pad", f"a pad (no site of group '{site.group}' carries one)"
            )
    return TactileLayout(grouping, convention, resolution, tuple(sites), pads)


def surface_maps(layout: TactileLayout) -> dict[str, SurfaceMap]:
    """One surface map per group, generated from the group's pad at the layout's resolution."""
    return {g: surface_map_from_pad(pad, layout.resolution, g) for g, pad in layout.pads.items()}


def tactile_sites(layout: TactileLayout, maps: dict[str, SurfaceMap] | None = None) -> list[TactileSite]:
    """Sites in file order; sites of one group share one SurfaceMap object (generated if not given)."""
    maps = surface_maps(layout) if maps is None else maps
    missing = sorted({s.group for s in layout.sites} - set(maps))
    if missing:
        raise KeyError(f"no surface map for groups {missing}")
    return [TactileSite(s.name, maps[s.group], s.attach_body) for s in layout.sites]
