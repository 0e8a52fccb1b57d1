"""An offscreen MuJoCo renderer that renders each modality once.

`mujoco.Renderer` renders the whole scene again for every modality it returns: RGB, then depth,
then segmentation. Depth and segmentation both come from the flat-coloured segmentation pass
(MuJoCo renders its depth pass that way too, for precision), so here one "id pass" reads the
depth buffer and the segment colours together: two scene renders per camera instead of three.
Only public MuJoCo API is used; the depth conversion follows `mujoco.Renderer`'s.

The segment colours are kept as `SegmentIds`: the per-pixel segment index (one byte per pixel while
the scene has under 255 geoms) and the frame's table from index to geom id. Labels map the index
through small per-frame tables (semantic and instance id per segment) in one lookup per image, so no
full-size geom-id image has to be made.
"""

from __future__ import annotations

import importlib
import os
from dataclasses import dataclass

import cv2
import mujoco
import numpy as np

_FLAGS = mujoco.mjtRndFlag
GL_BACKENDS = {"egl": "mujoco.egl", "osmesa": "mujoco.osmesa", "glfw": "mujoco.glfw"}


def gl_context_class():
    """The GL backend named by MUJOCO_GL (default egl: headless), resolved when a renderer is made.
    `mujoco.gl_context` is fixed when mujoco is first imported, which in the CLI happens before any
    of our modules could set a default: without MUJOCO_GL it picked GLFW and failed with no display."""
    backend = os.environ.setdefault("MUJOCO_GL", "egl").lower()
    if backend not in GL_BACKENDS:
        raise ValueError(f"MUJOCO_GL={backend!r}: expected one of {sorted(GL_BACKENDS)}")
    return importlib.import_module(GL_BACKENDS[backend]).GLContext


@dataclass(frozen=True)
class SegmentIds:
    """Segmentation of one id pass: `index` [H, W] (uint8 while the scene has under 255 geoms, else
    int64) is segment id + 1 per pixel, 0 = background; `geom` [K] int32 maps an index to its geom id
    (-1: background or a non-geom element such as a site)."""

    index: np.ndarray
    geom: np.ndarray

    def map(self, table: np.ndarray) -> np.ndarray:
        """[H, W] image of table[index] for a table of one value per index (len(geom) entries)."""
        if self.index.dtype == np.uint8:      # a 256-entry table lookup: OpenCV's LUT, ~4x numpy's take
            padded = np.full(256, table[0], table.dtype)      # unused indices read as background
            padded[: len(table)] = table
            return cv2.LUT(self.index, padded)
        return table.take(self.index)

    def geom_ids(self) -> np.ndarray:
        """[H, W] int32 geom id per pixel, -1 where no geom."""
        return self.map(self.geom)


class OffscreenRenderer:
    def __init__(self, model: mujoco.MjModel, width: int, height: int, max_geom: int = 10_000):
        if width > model.vis.global_.offwidth or height > model.vis.global_.offheight:
            raise ValueError(f"image {width}x{height} exceeds the model's offscreen buffer "
                             f"{model.vis.global_.offwidth}x{model.vis.global_.offheight} (visual/global offwidth)")
        self.model, self.width, self.height = model, width, height
        self._gl = gl_context_class()(width, height)
        self._gl.make_current()
        self._con = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._con)
        self._con.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self.scene = mujoco.MjvScene(model, maxgeom=max_geom)
        self._option = mujoco.MjvOption()
        self._camera = mujoco.MjvCamera()
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._scratch = np.empty((height, width), np.float64)

    def update(self, data: mujoco.MjData, camera_id: int, shadows: bool = False) -> None:
        """Place the scene's geoms for `data` as seen from a model camera."""
        self._camera.fixedcamid = camera_id
        mujoco.mjv_updateScene(self.model, data, self._option, None, self._camera,
                               mujoco.mjtCatBit.mjCAT_ALL, self.scene)
        self.scene.flags[_FLAGS.mjRND_SHADOW] = shadows
        self.scene.flags[_FLAGS.mjRND_REFLECTION] = shadows

    def color(self) -> np.ndarray:
        """HxWx3 uint8 image of the current scene."""
        self._gl.make_current()
        rgb = np.empty((self.height, self.width, 3), np.uint8)
        mujoco.mjr_render(self._rect, self.scene, self._con)
        mujoco.mjr_readPixels(rgb, None, self._rect, self._con)
        return np.flipud(rgb).copy()

    def depth_and_geoms(self, want_geoms: bool) -> tuple[np.ndarray, np.ndarray | None]:
        """Metric depth (HxW float32, far clip where nothing is hit) and, if asked, the geom id per
        pixel (HxW int32, -1 for background and non-geom elements), from one segmentation pass."""
        depth, segments = self.decode(*self.id_pass(want_geoms))
        return depth, (None if segments is None else segments.geom_ids())

    def id_pass(self, want_geoms: bool) -> tuple[np.ndarray, np.ndarray | None]:
        """The GL work of `depth_and_geoms`: render the segmentation pass and read back its depth
        buffer and (if asked) segment colours, bottom row first; `decode` turns them into images."""
        self._gl.make_current()
        flags = self.scene.flags
        saved = flags.copy()
        flags[_FLAGS.mjRND_SEGMENT] = True
        flags[_FLAGS.mjRND_IDCOLOR] = True
        colours = np.empty((self.height, self.width, 3), np.uint8) if want_geoms else None
        depth = np.empty((self.height, self.width), np.float32)
        try:
            mujoco.mjr_render(self._rect, self.scene, self._con)
            mujoco.mjr_readPixels(colours, depth, self._rect, self._con)
        finally:
            np.copyto(flags, saved)
        return depth, colours

    def decode(self, depth: np.ndarray, colours: np.ndarray | None) -> tuple[np.ndarray, SegmentIds | None]:
        """Metric depth and segments of an `id_pass` (before the scene is updated again). GL rows run
        bottom-up: the decoders read flipped views and write top-down arrays."""
        return self._metric_depth(depth[::-1]), (None if colours is None else self._segments(colours[::-1]))

    def _metric_depth(self, buffer: np.ndarray) -> np.ndarray:
        # reversed-z perspective projection undone in float64, as mujoco.Renderer does (same operations)
        extent = self.model.stat.extent
        znear = np.float32(self.model.vis.map.znear * extent)
        zfar = np.float32(self.model.vis.map.zfar * extent)
        c = np.float32(-0.5) * (-(zfar + znear) / (zfar - znear)) - np.float32(0.5)
        d = np.float32(-0.5) * (-(np.float32(2) * zfar * znear) / (zfar - znear))
        scratch = self._scratch     # kept between calls: a fresh 2.4 MB array per camera costs page faults
        np.add(buffer, np.float64(c), out=scratch)
        np.divide(np.float64(d), scratch, out=scratch)
        return scratch.astype(np.float32)

    def _segments(self, colours: np.ndarray) -> SegmentIds:
        # segid + 1 is packed little-endian into the colour (0 = background): one byte holds it while
        # the scene has under 255 geoms
        ngeom = self.scene.ngeom
        if ngeom < 255:
            index = np.ascontiguousarray(colours[..., 0])
        else:
            index = colours[..., 0].astype(np.int64)
            for channel in (1, 2):
                index |= colours[..., channel].astype(np.int64) << (8 * channel)
            np.minimum(index, ngeom, out=index)
        lookup = np.full(ngeom + 1, -1, np.int32)
        for g in self.scene.geoms[:ngeom]:
            if g.segid >= 0 and g.objtype == mujoco.mjtObj.mjOBJ_GEOM:
                lookup[g.segid + 1] = g.objid
        return SegmentIds(index, lookup)

    def close(self) -> None:
        if self._con is not None:
            self._gl.make_current()
            self._con.free()
            self._gl.free()
            self._con = None
