"""Tactile sensing of a compiled b2d scene: the TacMap counterpart of ``sim.render.CameraRig``.

Sites: every tactile site of the embodiment's hand on both sides, named as in the MuJoCo model
(``{side}_{site}``, left hand first, hand-file order). Each site's surface map is generated from
its declarative pad (attach-body frame) at the requested resolution; sites with identical pads share
one map and one set of rays, and the left hand's maps are the right hand's mirrored.
Targets: every geom of the task objects, their articulated links and the distractors
(``tactile.targets``), each in its own geom frame. The robot, the table and the floor are never
registered, so they never produce a tactile response.
Poses come from ``data`` after ``mj_kinematics`` (``sim.render.set_positions`` does that).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from sim.embodiment import load_embodiment
from tactile.pads import PadSpec, parse_pad
from tactile.quantize import encoding_description
from tactile.sensor import PASS2_BACKOFF_M, TactileFrame, TactileSensor, TactileSite
from tactile.surface import SurfaceMap, mirror_surface_map, surface_map_from_pad
from tactile.targets import clear_cache as clear_target_cache
from tactile.targets import geom_raycaster, target_geoms

if TYPE_CHECKING:
    from sim.registry import SensorProfile
    from sim.scene.builder import Scene


@dataclass(frozen=True)
class RigSite:
    name: str            # MuJoCo site name, e.g. "right_index_tip"
    side: str            # "left" | "right"
    finger: str
    group: str           # surface group of the hand file
    attach_body: str     # MuJoCo body whose frame holds the surface map
    surface: SurfaceMap  # full resolution; the sensor subsamples it by the step


@functools.lru_cache(maxsize=64)
def _surface(pad: PadSpec, resolution: int, group: str, mirrored: bool) -> SurfaceMap:
    """One map per distinct pad and side (cached: ~0.1 s per pad at 240 x 240)."""
    if mirrored:
        return mirror_surface_map(_surface(pad, resolution, group, False))
    return surface_map_from_pad(pad, resolution, group)


def clear_caches() -> None:
    """Forget the process-wide surface maps and target ray-cast scenes (they are rebuilt on demand)."""
    _surface.cache_clear()
    clear_target_cache()


def _pad_fields(pad) -> dict:
    """A hand description's pad as the mapping ``tactile.pads.parse_pad`` validates."""
    return {"center": np.asarray(pad.center).tolist(), "normal": np.asarray(pad.normal).tolist(),
            "axis": np.asarray(pad.axis).tolist(), "length": float(pad.length), "width": float(pad.width),
            "curvature_radius": float(pad.curvature_radius)}


def _rig_sites(layout, resolution: int) -> list[RigSite]:
    hand = load_embodiment(layout.embodiment).hand
    sites = []
    for side, side_layout in layout.sides.items():
        for i, spec in enumerate(hand.tactile.sites):
            name = f"{side}_{spec.name}"
            if name not in side_layout.tactile_bodies:
                raise ValueError(f"{hand.path}: tactile site '{spec.name}' has no MuJoCo site '{name}' in the scene")
            pad = parse_pad(_pad_fields(spec.pad), hand.path, f"tactile.sites[{i}].pad")
            surface = _surface(pad, resolution, spec.group, side == "left")
            sites.append(RigSite(name, side, spec.finger, spec.group, side_layout.tactile_bodies[name], surface))
    return sites


class TactileRig:
    """``capture(data)`` -> one ``TactileFrame`` (all sites, left hand first) at the current state."""

    def __init__(self, scene: Scene, resolution: int, step: int, max_range_m: float):
        model = scene.model
        self.embodiment = scene.layout.embodiment
        self.resolution = int(resolution)
        self.sites = tuple(_rig_sites(scene.layout, self.resolution))
        self.sensor = TactileSensor([TactileSite(s.name, s.surface, s.attach_body) for s in self.sites],
                                    step=step, max_range_m=max_range_m)
        self._body_ids = [model.body(s.attach_body).id for s in self.sites]
        self._targets = target_geoms(model, [*scene.object_names, *scene.distractor_names])
        for name, gid in self._targets:
            self.sensor.add_target(name, geom_raycaster(model, gid))

    @classmethod
    def for_profile(cls, scene: Scene, profile: SensorProfile) -> "TactileRig":
        """The rig a ``SensorProfile``'s ``tactile`` block asks for."""
        return cls(scene, profile.tactile_resolution, profile.tactile_step, profile.tactile_max_range_mm * 1e-3)

    @property
    def site_names(self) -> tuple[str, ...]:
        return self.sensor.site_names

    @property
    def target_names(self) -> tuple[str, ...]:
        return self.sensor.target_names

    @property
    def step(self) -> int:
        return self.sensor.step

    @property
    def shape(self) -> tuple[int, int]:
        return self.sensor.shape

    def capture(self, data: mujoco.MjData) -> TactileFrame:
        site_poses = {s.name: (data.xpos[b], data.xmat[b].reshape(3, 3)) for s, b in zip(self.sites, self._body_ids)}
        target_poses = {n: (data.geom_xpos[g], data.geom_xmat[g].reshape(3, 3)) for n, g in self._targets}
        return self.sensor.sense(site_poses, target_poses)

    def blank(self) -> TactileFrame:
        """An all-zero frame (no contact anywhere), for frames that could not be sensed."""
        shape = (len(self.sites), *self.shape)
        return TactileFrame(self.site_names, np.zeros(shape, np.uint8), np.zeros(shape, np.float32),
                            np.zeros(shape, bool), 0)

    def describe(self) -> dict:
        """JSON-able settings: sites, targets, grid, range, contact check and encoding."""
        return {
            "embodiment": self.embodiment,
            "sites": [{"name": s.name, "side": s.side, "finger": s.finger, "group": s.group,
                       "attach_body": s.attach_body} for s in self.sites],
            "targets": list(self.target_names),
            "resolution": self.resolution, "step": self.step, "shape": list(self.shape),
            "max_range_m": self.sensor.max_range_m,
            "surface": {"frame": "attach_body", "point_units": "mm", "normal_convention": "inward",
                        "source": "generated from the hand file's pads; left-hand maps are the right-hand "
                                  "maps mirrored (x negated)"},
            "contact_check": {"passes": 2, "pass2_backoff_m": PASS2_BACKOFF_M,
                              "rule": "a sample counts only if the reverse ray from just short of the first hit "
                                      "also meets the target"},
            "encoding": encoding_description(self.step),
        }
