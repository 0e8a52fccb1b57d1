"""Semantic and instance masks from MuJoCo's segmentation render.

Three forms of segmentation are accepted: mujoco.Renderer's [H, W, 2] (objid, objtype) image
(`render_segmentation`, after `update_scene` for the camera), an [H, W] geom-id image (-1 where no
geom) such as `sim.offscreen.OffscreenRenderer.depth_and_geoms` returns, and the
`sim.offscreen.SegmentIds` that the render stage's camera rig reads from its depth pass at no extra
render. `Segmenter.masks` maps each through the geom labels of `ids.LabelIds`; pixels that show no
geom (sky, or a site or other decoration) are background: semantic 0, instance 0. `SegmentIds` are
mapped through per-frame tables indexed by segment (a few hundred entries), one lookup per image.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from sim.labels.ids import LabelIds
from sim.offscreen import SegmentIds

_GEOM = int(mujoco.mjtObj.mjOBJ_GEOM)


def render_segmentation(renderer: mujoco.Renderer) -> np.ndarray:
    """[H, W, 2] int32 (objid, objtype) per pixel of the renderer's current scene; -1 where empty."""
    renderer.enable_segmentation_rendering()
    try:
        return renderer.render()
    finally:
        renderer.disable_segmentation_rendering()


@dataclass(frozen=True)
class Masks:
    semantic: np.ndarray    # [H, W] uint8, ids.semantic_names
    instance: np.ndarray    # [H, W] uint16, ids.instance_names (0 = no object)


class Segmenter:
    """Maps segmentation renders to masks through lookup tables built once per model."""

    def __init__(self, ids: LabelIds):
        # index 0 holds "no geom": a pixel's table index is geom id + 1, or 0
        self.semantic_lut = np.concatenate([[0], ids.geom_semantic]).astype(np.uint8)
        self.instance_lut = np.concatenate([[0], ids.geom_instance]).astype(np.uint16)
        self.ngeom = len(ids.geom_semantic)

    def masks(self, seg: np.ndarray | SegmentIds) -> Masks:
        """Masks of `SegmentIds`, an [H, W] geom-id image (-1 = none) or an [H, W, 2] (objid, objtype) image."""
        if isinstance(seg, SegmentIds):
            index = seg.geom.astype(np.intp) + 1       # per segment: the tables' index of its geom
            if index.size and (index.max() > self.ngeom or index.min() < 0):
                raise ValueError(f"segmentation: geom ids {int(seg.geom.min())}..{int(seg.geom.max())} outside "
                                 f"-1..{self.ngeom - 1} (the model's geoms)")
            return Masks(seg.map(self.semantic_lut[index]), seg.map(self.instance_lut[index]))
        seg = np.asarray(seg)
        if seg.ndim == 3 and seg.shape[2] == 2:
            geom = np.where(seg[..., 1] == _GEOM, seg[..., 0], -1)
        elif seg.ndim == 2 and seg.dtype.kind == "i":
            geom = seg
        else:
            raise ValueError(f"segmentation image: expected [H, W] integer geom ids or [H, W, 2] (objid, objtype), "
                             f"got shape {seg.shape} of {seg.dtype}")
        index = geom.astype(np.intp)      # one index array serves both tables
        index += 1
        if index.size and (index.max() > self.ngeom or index.min() < 0):
            raise ValueError(f"segmentation image: geom ids {int(geom.min())}..{int(geom.max())} outside "
                             f"-1..{self.ngeom - 1} (the model's geoms)")
        return Masks(self.semantic_lut.take(index), self.instance_lut.take(index))
