"""TacMap layer of b2d: surface maps, surface-aligned ray casting and tacmap encoding.

Modules: ``pads`` (pad meshes from hand files), ``registry`` (surface assets of a hand's tactile
groups; the hand file's block is read by ``sim.embodiment``), ``surface`` (surface maps and their .npy
assets), ``raycast`` / ``broadphase`` / ``sensor`` (per-frame sensing), ``quantize`` (the paper's
depth encoding), ``heatmap`` (figures) and ``bench`` (throughput); ``targets`` (scene geoms as
ray-cast targets) and ``rig`` (a compiled scene's sites and targets, sensed per frame) bind it to
b2d's MuJoCo scenes. Nothing here imports Dagster.
"""

from tactile.pads import PadSpec, build_pad_mesh, parse_pad
from tactile.quantize import encode_tacmap
from tactile.registry import surface_assets
from tactile.sensor import TactileFrame, TactileSensor, TactileSite
from tactile.surface import SurfaceMap, load_surface_map, save_surface_map, surface_map_from_pad

__all__ = [
    "PadSpec", "build_pad_mesh", "parse_pad", "encode_tacmap", "surface_assets", "TactileFrame", "TactileSensor",
    "TactileSite", "SurfaceMap",
    "load_surface_map", "save_surface_map", "surface_map_from_pad",
]
