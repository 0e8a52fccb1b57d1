"""Tactile frames of a render, in the episode layout (``schema.TACTILE_*``).

The render stage poses the scene for each frame and asks this module for that frame's tactile
datasets next to the camera images; a frame that cannot be sensed is stored as "no contact" and
flagged, like a failed camera frame, instead of aborting the episode.
"""

from __future__ import annotations

import json
import logging

import mujoco

from episodes import schema
from sim.registry import SensorProfile
from tactile.rig import TactileRig
from tactile.sensor import TactileFrame

log = logging.getLogger(__name__)


class TactileFrames:
    """``static()`` once per file, then ``capture(data)`` -> (datasets, error text) per frame."""

    def __init__(self, scene, profile: SensorProfile):
        self.profile = profile
        self.rig = TactileRig.for_profile(scene, profile)

    def static(self) -> dict:
        meta = {"profile": self.profile.name, "profile_hash": self.profile.content_hash, **self.rig.describe()}
        out = {f"{schema.TACTILE_ROOT}/meta": json.dumps(meta, sort_keys=True),
               f"{schema.TACTILE_ROOT}/site_names": list(self.rig.site_names)}
        for site in self.rig.sites:
            stored = site.surface.subsample(self.rig.step)  # the grid the frames are sampled on
            out[f"{schema.TACTILE_ROOT}/surface/{site.name}/point_mm"] = stored.point_mm
            out[f"{schema.TACTILE_ROOT}/surface/{site.name}/normal"] = stored.normal
        return out

    def capture(self, data: mujoco.MjData) -> tuple[dict, str]:
        try:
            frame, error = self.rig.capture(data), ""
        except Exception as exc:   # keep the episode: flag the frame instead of aborting
            log.warning("tactile sensing failed: %s", exc)
            frame, error = self.rig.blank(), f"tactile failed: {exc}"
        return frame_datasets(frame), error


def frame_datasets(frame: TactileFrame) -> dict:
    """One frame's per-site datasets: tacmap (uint8), distance_along_normal_m (float32), contact_mask (bool)."""
    out = {}
    for i, site in enumerate(frame.site_names):
        out[schema.tactile_path("tacmap", site)] = frame.tacmap[i]
        out[schema.tactile_path("distance_along_normal_m", site)] = frame.distance_m[i]
        out[schema.tactile_path("contact_mask", site)] = frame.mask[i]
    return out
