"""The kept passes of a still camera (sim.offscreen): which geoms and cameras never move, what else a
pass depends on (its key), and how two passes of disjoint geom sets merge into the pass of all of them.

Pure functions over MuJoCo's model, scene and read-back buffers; the renderer decides when to use them.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import cv2
import mujoco
import numpy as np


def welded_bodies(model: mujoco.MjModel) -> np.ndarray:
    """[nbody] bool: the world body and bodies welded to it (no joint on the way, not mocap)."""
    welded = np.zeros(model.nbody, bool)
    welded[0] = True
    for b in range(1, model.nbody):        # a parent comes before its children
        welded[b] = welded[model.body_parentid[b]] and model.body_jntnum[b] == 0 and model.body_mocapid[b] < 0
    return welded


def still_cameras(model: mujoco.MjModel, welded: np.ndarray) -> set[int]:
    """Model cameras whose pose never changes: fixed mode on a welded body."""
    fixed = int(mujoco.mjtCamLight.mjCAMLIGHT_FIXED)
    return {i for i in range(model.ncam) if welded[model.cam_bodyid[i]] and int(model.cam_mode[i]) == fixed}


class ViewKey:
    """What a pass draws besides its geoms, as bytes: both GL cameras, the lights, the flags and the frame.
    Read straight from the scene's memory where the bindings' field addresses show its layout (a few
    microseconds), else field by field."""

    _LIGHT_HEAD = ("id", "type", "texid", "headlight", "castshadow")    # may lie before `pos` in the struct
    _LIGHT_FIELDS = _LIGHT_HEAD + ("pos", "dir", "ambient", "diffuse", "specular", "attenuation", "cutoff",
                                   "exponent", "bulbradius", "intensity", "range", "softness")

    def __init__(self, scene: mujoco.MjvScene):
        self.scene = scene
        cam0, cam1 = scene.camera[0], scene.camera[1]
        base = cam0.pos.ctypes.data
        # mjvGLCamera: pos, forward, up, then six frustum floats and orthographic (64 bytes)
        self._cameras = base if (cam1.pos.ctypes.data - base == 64 and cam0.forward.ctypes.data - base == 12
                                 and cam0.up.ctypes.data - base == 24) else None
        lights = scene.lights
        self._lights = lights[0].pos.ctypes.data if len(lights) > 1 else None
        self._light_stride = lights[1].pos.ctypes.data - self._lights if self._lights is not None else 0

    def __call__(self) -> bytes:
        scene = self.scene
        if self._cameras is not None:
            parts = [ctypes.string_at(self._cameras, 128)]
        else:
            parts = [np.array([*c.pos, *c.forward, *c.up, c.frustum_center, c.frustum_width, c.frustum_bottom,
                               c.frustum_top, c.frustum_near, c.frustum_far, c.orthographic]).tobytes()
                     for c in (scene.camera[0], scene.camera[1])]
        n = scene.nlight
        if n and self._lights is not None and self._light_stride > 0 and n < len(scene.lights):
            # from the first light's `pos` to the end of the last light: every field but the first light's head
            parts.append(ctypes.string_at(self._lights, n * self._light_stride))
            first = scene.lights[0]
            parts.append(repr([getattr(first, name, None) for name in self._LIGHT_HEAD]).encode())
        elif n:
            parts += [np.asarray(getattr(scene.lights[i], name)).tobytes()
                      for i in range(n) for name in self._LIGHT_FIELDS if hasattr(scene.lights[i], name)]
        parts += [scene.flags.tobytes(), np.array([n, scene.framewidth]).tobytes(), scene.framergb.tobytes()]
        return b"".join(parts)


@dataclass
class Layer:
    """One still camera's passes of the welded geoms alone (GL rows, bottom row first): `ids` (depth
    buffer, segment colours) and `rgb`, made when first needed; valid while `key` is unchanged."""

    key: bytes
    ids: tuple[np.ndarray, np.ndarray] | None = None
    rgb: np.ndarray | None = None


def segment_index(colours: np.ndarray, ngeom: int) -> np.ndarray:
    """Segment index (segid + 1, 0 = none) per pixel of an id pass's colours."""
    if ngeom < 255:
        return cv2.extractChannel(colours, 0)
    return colours[..., 0].astype(np.int64) | colours[..., 1].astype(np.int64) << 8 \
        | colours[..., 2].astype(np.int64) << 16


def merge_id_passes(fixed: tuple[np.ndarray, np.ndarray], moving: tuple[np.ndarray, np.ndarray],
                     draw_order: np.ndarray, ngeom: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The id pass of all geoms from the passes of two disjoint sets of them, written into `moving`'s
    arrays: per pixel the fragment the depth test keeps (GL_GEQUAL, reversed z, cleared to 0: the greater
    depth value wins; on a tie the geom drawn later, `draw_order[segment index]`). Returns depth, colours
    and the pixels no `moving` geom owns (a `fixed` geom's or background)."""
    f_depth, f_colours = fixed
    m_depth, m_colours = moving
    keep_fixed = f_depth >= m_depth
    m_index = segment_index(m_colours, ngeom)
    ties = np.flatnonzero((f_depth == m_depth) & (m_index != 0))
    if ties.size:       # a moving geom's fragment at the same depth: the later geom's, or the one there is
        fi = segment_index(f_colours, ngeom).reshape(-1)[ties]
        mi = m_index.reshape(-1)[ties]
        keep_fixed.reshape(-1)[ties] = (fi != 0) & (draw_order[fi] > draw_order[mi])
    mask = keep_fixed.view(np.uint8)        # OpenCV's masked copy: ~30x numpy's copyto(where=) here
    cv2.copyTo(f_depth, mask, m_depth)
    cv2.copyTo(f_colours, mask, m_colours)
    return m_depth, m_colours, keep_fixed
