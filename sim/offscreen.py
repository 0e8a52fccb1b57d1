"""An offscreen MuJoCo renderer that renders each modality once.

`mujoco.Renderer` renders the whole scene again for every modality it returns: RGB, then depth,
then segmentation. Depth and segmentation both come from the flat-coloured segmentation pass
(MuJoCo renders its depth pass that way too, for precision), so here one "id pass" reads the
depth buffer and the segment colours together: two scene renders per camera instead of three.
Only public MuJoCo API is used; the depth conversion follows `mujoco.Renderer`'s.
"""

from __future__ import annotations

import importlib
import os

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
        self._gl.make_current()
        flags = self.scene.flags
        saved = flags.copy()
        flags[_FLAGS.mjRND_SEGMENT] = True
        flags[_FLAGS.mjRND_IDCOLOR] = True
        colours = np.empty((self.height, self.width, 3), np.uint8)
        depth = np.empty((self.height, self.width), np.float32)
        try:
            mujoco.mjr_render(self._rect, self.scene, self._con)
            mujoco.mjr_readPixels(colours if want_geoms else None, depth, self._rect, self._con)
        finally:
            np.copyto(flags, saved)
        metric = np.flipud(self._metric_depth(depth)).copy()
        return metric, (np.flipud(self._geom_ids(colours)).copy() if want_geoms else None)

    def _metric_depth(self, buffer: np.ndarray) -> np.ndarray:
        # reversed-z perspective projection undone in float64, as mujoco.Renderer does
        extent = self.model.stat.extent
        znear = np.float32(self.model.vis.map.znear * extent)
        zfar = np.float32(self.model.vis.map.zfar * extent)
        c = np.float32(-0.5) * (-(zfar + znear) / (zfar - znear)) - np.float32(0.5)
        d = np.float32(-0.5) * (-(np.float32(2) * zfar * znear) / (zfar - znear))
        return (d / (buffer.astype(np.float64) + c)).astype(np.float32)

    def _geom_ids(self, colours: np.ndarray) -> np.ndarray:
        seg = colours.astype(np.int64)
        segid = seg[..., 0] + (seg[..., 1] << 8) + (seg[..., 2] << 16)   # 0 = background
        lookup = np.full(self.scene.ngeom + 1, -1, np.int32)
        for g in self.scene.geoms[: self.scene.ngeom]:
            if g.segid >= 0 and g.objtype == mujoco.mjtObj.mjOBJ_GEOM:
                lookup[g.segid + 1] = g.objid
        return lookup[np.clip(segid, 0, self.scene.ngeom)]

    def close(self) -> None:
        if self._con is not None:
            self._gl.make_current()
            self._con.free()
            self._gl.free()
            self._con = None
