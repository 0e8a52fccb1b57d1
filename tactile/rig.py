"""Tactile sensing of a compiled b2d scene: the TacMap counterpart of ``sim.render.CameraRig``.

Sites: every tactile site of the embodiment's hand on both sides, named as in the MuJoCo model
(``{side}_{site}``, left hand first, hand-file order). Each site uses its group's surface asset
(``tactile.registry``, groups from the hand's ``tactile`` block): all sites of a group share one
SurfaceMap, hence one set of rays. An asset is rasterised from the compiled pad geom of the group's
right-hand site, the geom that physically makes contact, just as ``tactile.targets`` builds ray targets from compiled geoms:
the tactile surface lies where MuJoCo's contacts happen, edges included. (The pad geom is a flat
box, so a hand pad's ``curvature_radius`` does not shape it; the rounded sheet of ``tactile.pads``
lay 3.2-5.3 mm under the box at the pad edges, where contacts went unseen.) Left assets are the
right ones reflected by the embodiment's mirror; ``side_shared`` assets serve both hands unchanged.
Targets: every geom of the task objects, their articulated links and the distractors
(``tactile.targets``), each in its own geom frame. The robot, the table and the floor are never
registered, so they never produce a tactile response.
Poses come from ``data`` after ``mj_kinematics`` (``sim.render.set_positions`` does that).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np
import trimesh

from sim.embodiment import load_embodiment
from sim.embodiment.builder import PAD_GEOM_SUFFIX
from tactile.quantize import encoding_description
from tactile.registry import surface_assets
from tactile.sensor import PASS2_BACKOFF_M, TactileFrame, TactileSensor, TactileSite
from tactile.surface import SurfaceMap
from tactile.targets import clear_cache as clear_target_cache
from tactile.targets import geom_mesh_in_body, geom_raycaster, target_geoms

if TYPE_CHECKING:
    from sim.embodiment import HandDescription, RobotLayout
    from sim.embodiment.description import TactileSpec
    from sim.registry import SensorProfile
    from sim.scene.builder import Scene

ASSET_SIDE = "right"      # hand files describe the right hand; left assets are reflected from it


@dataclass(frozen=True)
class RigSite:
    name: str            # MuJoCo site name, e.g. "right_index_tip"
    side: str            # "left" | "right"
    finger: str
    group: str           # surface group of the hand file, e.g. "4F"
    asset: str           # surface asset of the group on this side, e.g. "R4F"
    attach_body: str     # MuJoCo body whose frame holds the surface map
    surface: SurfaceMap  # full resolution; the sensor subsamples it by the step


_ASSETS: dict[tuple, dict[str, SurfaceMap]] = {}  # (hand, resolution, pad geometry digest) -> assets


def clear_caches() -> None:
    """Forget the process-wide surface assets and target ray-cast scenes (they are rebuilt on demand)."""
    _ASSETS.clear()
    clear_target_cache()


def pad_contact_meshes(model: mujoco.MjModel, tactile: TactileSpec) -> dict[str, trimesh.Trimesh]:
    """Group -> the compiled pad geom of its first right-hand site, in that site's attach-body frame."""
    meshes = {}
    for group in tactile.groups.values():
        name = f"{ASSET_SIDE}_{group.sites[0]}{PAD_GEOM_SUFFIX}"
        geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)
        if geom < 0:
            raise ValueError(f"tactile group '{group.name}': the model has no pad geom '{name}'")
        meshes[group.name] = geom_mesh_in_body(model, geom)
    return meshes


def _assets(model: mujoco.MjModel, hand: str, tactile: TactileSpec, resolution: int) -> dict[str, SurfaceMap]:
    """The hand's surface assets, cached per pad geometry (~0.1 s per group at 240 x 240)."""
    meshes = pad_contact_meshes(model, tactile)
    digest = hashlib.sha256()
    for group, mesh in meshes.items():
        for part in (group.encode(), np.asarray(mesh.vertices, np.float64).tobytes(), np.asarray(mesh.faces).tobytes()):
            digest.update(part)
    key = (hand, int(resolution), digest.hexdigest())
    if key not in _ASSETS:
        _ASSETS[key] = surface_assets(tactile, resolution, meshes)
    return _ASSETS[key]


def _rig_sites(model: mujoco.MjModel, robot: RobotLayout, hand: HandDescription, tactile: TactileSpec,
               resolution: int) -> list[RigSite]:
    assets = _assets(model, str(hand.path), tactile, resolution)
    sites = []
    for side, side_layout in robot.sides.items():
        for spec in tactile.sites:
            name = f"{side}_{spec.name}"
            if name not in side_layout.tactile_bodies:
                raise ValueError(f"{hand.path}: tactile site '{spec.name}' has no MuJoCo site '{name}' in the scene")
            asset = tactile.asset_of(side, spec.name)
            sites.append(RigSite(name, side, spec.finger, spec.group, asset, side_layout.tactile_bodies[name],
                                 assets[asset]))
    return sites


class TactileRig:
    """``capture(data)`` -> one ``TactileFrame`` (all sites, left hand first) at the current state."""

    def __init__(self, model: mujoco.MjModel, robot: RobotLayout, target_roots, resolution: int, step: int,
                 max_range_m: float):
        """``target_roots``: the bodies whose geoms (and whose descendants' geoms) rays may hit."""
        self.embodiment = robot.embodiment
        self.resolution = int(resolution)
        hand = load_embodiment(robot.embodiment).hand
        tactile = hand.tactile
        self.grouping = tactile.grouping
        self.sites = tuple(_rig_sites(model, robot, hand, tactile, self.resolution))
        self.sensor = TactileSensor([TactileSite(s.name, s.surface, s.attach_body) for s in self.sites],
                                    step=step, max_range_m=max_range_m)
        self._body_ids = [model.body(s.attach_body).id for s in self.sites]
        self._targets = target_geoms(model, list(target_roots))
        for name, gid in self._targets:
            self.sensor.add_target(name, geom_raycaster(model, gid))

    @classmethod
    def for_profile(cls, scene: Scene, profile: SensorProfile) -> "TactileRig":
        """The rig a ``SensorProfile``'s ``tactile`` block asks for, on a task scene."""
        return cls(scene.model, scene.layout, [*scene.object_names, *scene.distractor_names],
                   profile.tactile_resolution, profile.tactile_step, profile.tactile_max_range_mm * 1e-3)

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
        """JSON-able settings: grouping, sites and their assets, targets, grid, range, contact check, encoding."""
        return {
            "embodiment": self.embodiment,
            "grouping": self.grouping,
            "sites": [{"name": s.name, "side": s.side, "finger": s.finger, "group": s.group, "asset": s.asset,
                       "attach_body": s.attach_body} for s in self.sites],
            "targets": list(self.target_names),
            "resolution": self.resolution, "step": self.step, "shape": list(self.shape),
            "max_range_m": self.sensor.max_range_m,
            "surface": {"frame": "attach_body", "point_units": "mm", "normal_convention": "inward",
                        "source": "one asset per group and side, rasterised from the compiled pad geom of the "
                                  "group's right-hand site; left assets are the right ones reflected by the "
                                  "embodiment's mirror, side_shared assets serve both hands unchanged"},
            "contact_check": {"passes": 2, "pass2_backoff_m": PASS2_BACKOFF_M,
                              "rule": "a sample counts only if the reverse ray from just short of the first hit "
                                      "also meets the target"},
            "encoding": encoding_description(self.step),
        }
