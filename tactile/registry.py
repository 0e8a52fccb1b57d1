"""The tactile registry: a hand's surface groups as surface assets, one per group and side.

A hand file's ``tactile`` block (grouping policy, groups with their per-side asset names and pad,
sites) is read once, with the rest of the hand, by ``sim.embodiment.description`` (format and the
paper's policies are described there): ``load_hand(name).tactile`` is the registry entry, with its
site-to-asset map (``TactileSpec.site_assets``). This module builds the assets.
"""

from __future__ import annotations

import trimesh

from sim.embodiment.description import TactileSpec
from sim.embodiment.mirror import M as MIRROR
from tactile.surface import SurfaceMap, reflected_surface_map, surface_map_from_pad


def surface_assets(
    layout: TactileSpec, resolution: int | None = None, contact_meshes: dict[str, trimesh.Trimesh] | None = None
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
