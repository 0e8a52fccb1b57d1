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

Where the time goes (llvmpipe on the calling thread; one 64x48 / 128x96 colour pass of a demonstration
scene, 70 primitive geoms, ~6 / ~7 ms): not in the scene update (`mjv_updateScene`, ~3 us), context
switches (~7 us) or read-backs and flips (<25 us); clearing, GL state and the skybox take ~0.4 / ~0.9 ms;
the rest is the triangles of MuJoCo's tessellated primitives (a capsule is ~1,800 triangles at the
default quality, the scene ~88k): vertex work for every geom drawn (~2.2 ms with all of them behind
the camera), then set-up and rasterization of those in view, little of it per pixel. So each render
draws only the geoms that can reach a pixel, which leaves every output byte as it was:
- the colour and id passes skip geoms whose bounding sphere lies wholly outside the camera's view
  frustum (they would be clipped away anyway);
- a colour pass that follows the same camera's id pass draws only the geoms that own a pixel of it.
  A pixel keeps the last fragment of greatest depth, and both passes rasterize the same triangles to
  the same depths, so a geom that owns no pixel of the id pass owns none of the colour pass either
  (skybox and haze test against the same depth buffer). Not used with transparency, reflective
  geoms, planes seen from behind, wireframe, multisampling, shadows or reflections, where it would
  not hold.
At a coarse tessellation (a profile's `tessellation`, e.g. (8, 4)) a pass costs ~2.7x less and what is left
is mostly per geom drawn (~25-35 us a geom a pass in llvmpipe, whatever its triangles), then clearing and the
skybox. Measured alternatives that did not win (issue 22): Embree ray casting of the same primitives for
depth and ids (embreex, 128x96 preview cameras: rays alone cost more than the GL id pass at (8, 4), and the
scene must be rebuilt every frame, as embreex has no instancing); OSMesa instead of EGL (same bytes, same
time). Not tried: one framebuffer with a viewport per camera, which could save only the read-backs (~0.1 ms
a 128x96 pass): an id pass with no geom costs ~0.01 ms, a colour pass ~0.5 ms of skybox that each viewport
would still draw.
A camera that never moves (on the world or a body welded to it) sees the geoms welded to the world
(table, floor, stands) the same way in every frame. Their id and colour passes are rendered once and kept
(`sim.still_layers`, while the camera, lights, flags and those geoms' records stay byte-identical); each frame
renders only the other geoms and merges per pixel by the depth test MuJoCo sets (GL_GEQUAL on
reversed z: the nearer fragment wins, a tie goes to the geom drawn later), which is the pixel the whole
scene would give: depth and segment colours from the id passes, RGB from the pass of the geom that owns
the pixel (as for the colour pass's pixel owners), the layer's RGB wherever no moving geom shows. So
the moving geoms' colour pass can leave out the skybox (~0.4 ms a 128x96 pass in llvmpipe) when it lies
behind all of them. The floor, table and stands cover most of a still camera's pixels: with the skybox,
those cameras' passes cost ~30% less (`b2d bench replay`: still_layers_vs_whole_passes).
Geom records are moved in the scene's own buffer (a numpy view checked against the bindings' field
views when the renderer is made; without a match the renderer draws every geom) and put back after
each render, keeping their segmentation ids, so segment colours do not change.

The renderers of a thread share one GL context (the first MuJoCo context in a fresh GL context costs
llvmpipe ~200 ms of CPU, a later one ~3 ms); each keeps its own MuJoCo context and offscreen framebuffer,
bound again whenever it renders. Without shadows a renderer's MuJoCo context has no shadow map (MuJoCo
allocates a 4096-square one by default, ~45 ms). A renderer must free its GL objects with their GL context
current: `close()` does, and so does a renderer that is garbage-collected without it (a finalizer), which
once deleted the objects of whichever context was current - another renderer's, whose images then came
out as noise.
"""

from __future__ import annotations

import ctypes
import importlib
import logging
import math
import os
import threading
import weakref
from dataclasses import dataclass

import cv2
import mujoco
import numpy as np

from sim.still_layers import Layer, ViewKey, merge_id_passes, still_cameras, welded_bodies

log = logging.getLogger(__name__)

_FLAGS = mujoco.mjtRndFlag
_G = mujoco.mjtGeom
_SPHERE, _CAPSULE, _ELLIPSOID, _CYLINDER, _BOX, _MESH, _PLANE = (   # plain ints: numpy compares enums slowly
    int(_G.mjGEOM_SPHERE), int(_G.mjGEOM_CAPSULE), int(_G.mjGEOM_ELLIPSOID), int(_G.mjGEOM_CYLINDER),
    int(_G.mjGEOM_BOX), int(_G.mjGEOM_MESH), int(_G.mjGEOM_PLANE))
_OBJ_GEOM = int(mujoco.mjtObj.mjOBJ_GEOM)
# mjvGeom as laid out in MuJoCo's mjvisualize.h (4.0), checked against the bindings per renderer
_GEOM_DTYPE = np.dtype([
    ("type", "i4"), ("dataid", "i4"), ("objtype", "i4"), ("objid", "i4"), ("category", "i4"), ("matid", "i4"),
    ("texid", "i4"), ("texuniform", "i4"), ("texcoord", "i4"), ("segid", "i4"),
    ("size", "f4", 3), ("pos", "f4", 3), ("mat", "f4", 9), ("rgba", "f4", 4),
    ("emission", "f4"), ("specular", "f4"), ("shininess", "f4"), ("reflectance", "f4"), ("texrepeat", "f4", 2),
    ("castshadow", "u1"), ("label", "u1", 100), ("camdist", "f4"), ("modelrbound", "f4"), ("transparent", "u1"),
], align=True)
_OPAQUE_ALPHA = np.float32(0.995)     # mjr_render treats a geom of lower alpha as transparent
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


def _geom_records(scene: mujoco.MjvScene) -> np.ndarray | None:
    """A structured numpy view of the scene's geom buffer (maxgeom records), or None when MuJoCo's
    mjvGeom is not laid out as `_GEOM_DTYPE` says: the array fields' addresses and a probe record,
    written through the bindings and read back, must agree."""
    geoms = scene.geoms
    if len(geoms) < 2:
        return None
    a, b = geoms[0], geoms[1]
    try:
        base = a.pos.ctypes.data - _GEOM_DTYPE.fields["pos"][1]
        if b.pos.ctypes.data - a.pos.ctypes.data != _GEOM_DTYPE.itemsize:
            return None
        for name in ("size", "pos", "mat", "rgba", "texrepeat"):
            if getattr(a, name).ctypes.data != base + _GEOM_DTYPE.fields[name][1]:
                return None
        view = np.frombuffer((ctypes.c_char * (_GEOM_DTYPE.itemsize * scene.maxgeom)).from_address(base),
                             _GEOM_DTYPE)
        probe = {"type": 3, "dataid": -5, "objtype": 5, "objid": 17, "category": 2, "matid": 9, "texid": 4,
                 "texuniform": 1, "texcoord": 1, "segid": 23, "emission": 0.25, "specular": 0.5,
                 "shininess": 0.75, "reflectance": 0.125, "castshadow": 1, "camdist": 1.5, "modelrbound": 2.5,
                 "transparent": 1}
        for name, value in probe.items():
            setattr(a, name, value)
        a.label = "probe"
        record = view[0]
        ok = all(float(record[name]) == value for name, value in probe.items()) \
            and record["label"][:6].tobytes() == b"probe\0"
        view[:2] = np.zeros(2, _GEOM_DTYPE)      # the scene is empty (ngeom 0): nothing else to restore
    except (AttributeError, TypeError, ValueError):
        return None
    return view if ok else None


def _bounding_radii(geoms: np.ndarray) -> np.ndarray:
    """Radius about `pos` holding every drawn triangle, with a margin for float rounding: primitives
    from their size, meshes from the model's rbound; inf for anything else (planes, height fields,
    lines, flex, skins), which is always drawn."""
    size = geoms["size"].astype(np.float64)
    kind = geoms["type"]
    radius = np.full(len(geoms), np.inf)
    rims = size[:, :2].max(axis=1)
    for gtype, r in ((_SPHERE, size.max(axis=1)),
                     (_ELLIPSOID, size.max(axis=1)),
                     (_CAPSULE, rims + size[:, 2]),         # open cylinder + end caps of radius <= rim
                     (_CYLINDER, np.hypot(rims, size[:, 2])),
                     (_BOX, np.linalg.norm(size, axis=1)),
                     (_MESH, np.where(geoms["modelrbound"] > 0, geoms["modelrbound"], np.inf))):
        sel = kind == gtype
        radius[sel] = r[sel]
    return radius * 1.001 + 1e-3


def _make_context(model: mujoco.MjModel, shadows: bool) -> mujoco.MjrContext:
    """MuJoCo's GL resources for `model`. Without shadows the context gets no shadow map: MuJoCo
    allocates one of `visual/quality/shadowsize` squared (4096 by default) for every context, ~45 ms of a
    ~50 ms context in llvmpipe, and reads it only when a scene asks for shadows. The model is left as it was."""
    size = int(model.vis.quality.shadowsize)
    if not shadows:
        model.vis.quality.shadowsize = 0
    try:
        return mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150)
    finally:
        model.vis.quality.shadowsize = size


def _scene_capacity(model: mujoco.MjModel) -> int:
    """Visual geoms a scene may hold: four per model element MuJoCo may draw (a b2d scene draws one per geom),
    at least 1,000. mujoco.Renderer's 10,000 cost ~36 ms of every renderer's set-up to allocate."""
    return max(1_000, 4 * (model.ngeom + model.nsite + model.ntendon + model.nflex + model.nskin))


_THREAD_GL = threading.local()


def _thread_gl_context(width: int, height: int):
    """The GL context shared by the renderers of the calling thread, made by the first of them. Mesa's
    llvmpipe spends ~200 ms of CPU on the first MuJoCo context in a fresh GL context and ~3 ms on each
    later one, so a render file or rollout after the first no longer pays it. A GL context is current on
    one thread at a time, hence one per thread; the process id guards against a forked copy. Renderers
    draw into their own MuJoCo offscreen framebuffers, so the context's own surface size never matters."""
    key = (os.getpid(), os.environ.get("MUJOCO_GL", "egl").lower())
    if getattr(_THREAD_GL, "key", None) != key:
        _THREAD_GL.context, _THREAD_GL.key = gl_context_class()(width, height), key
    return _THREAD_GL.context


def _release(gl, con, thread_id: int) -> None:
    """Free an MjrContext's GL objects with its own GL context current (restoring whichever was current:
    a finalizer may run in the middle of another renderer's work). The shared GL context is current on
    its own thread, so a renderer collected on another thread leaves its objects to that context."""
    if threading.get_ident() != thread_id:
        log.warning("an OffscreenRenderer collected on another thread than its own: its GL objects are "
                    "left until its thread's GL context ends (close() renderers on their own thread)")
        return
    with gl.as_current():
        con.free()


class OffscreenRenderer:
    """`still_layers` False renders every pass of every camera whole (the reference for the kept
    passes of the welded geoms; benchmarks compare both)."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int, max_geom: int | None = None,
                 still_layers: bool = True, shadows: bool = False):
        if width > model.vis.global_.offwidth or height > model.vis.global_.offheight:
            raise ValueError(f"image {width}x{height} exceeds the model's offscreen buffer "
                             f"{model.vis.global_.offwidth}x{model.vis.global_.offheight} (visual/global offwidth)")
        self.model, self.width, self.height = model, width, height
        self._gl = _thread_gl_context(width, height)
        self._gl.make_current()
        self.shadows = shadows
        self._con = _make_context(model, shadows)
        # frees the GL objects in the context they were made in, from close() or when it is collected
        self._finalizer = weakref.finalize(self, _release, self._gl, self._con, threading.get_ident())
        self._make_current()
        self._con.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        self._rect = mujoco.MjrRect(0, 0, width, height)
        max_geom = max_geom or _scene_capacity(model)
        self.scene = mujoco.MjvScene(model, maxgeom=max_geom)
        self._option = mujoco.MjvOption()
        self._camera = mujoco.MjvCamera()
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._scratch = np.empty((height, width), np.float64)
        self._geoms = _geom_records(self.scene)        # None: draw every geom
        self._records = None if self._geoms is None else self._geoms.view(np.uint8).reshape(max_geom, -1)
        self._placement = 0                            # counts update() calls
        self._set: tuple | None = None           # see _geom_set
        self._view: tuple | None = None          # (placement, in view, always drawn, owners apply): see _drawn
        self._owners: tuple[int, np.ndarray] | None = None   # (placement, segids owning a pixel of its id pass)
        welded = welded_bodies(model)
        self._welded_geom = welded[model.geom_bodyid]
        self._still_cameras = still_cameras(model, welded) if still_layers and self._welded_geom.any() else set()
        self._layers: dict[int, Layer] = {}       # still camera id -> its welded geoms' passes
        self._view_key = ViewKey(self.scene)
        # the skybox cylinder's nearest facet, as a fraction of the far clip (tessellated when the context was made)
        self._skybox_near = 0.7 * math.cos(math.pi / max(3, int(model.vis.quality.numslices)))
        self._camera_id = -1
        self._welded_placed: tuple[bytes, np.ndarray | None] | None = None    # see _still_layer
        # (placement, welded geoms among the placed, pixels no moving geom owns, layer): see id_pass
        self._merged: tuple[int, np.ndarray, np.ndarray, Layer] | None = None

    def _make_current(self) -> None:
        """This renderer's GL context and its own offscreen framebuffer (another renderer of the thread
        may have bound its own since)."""
        self._gl.make_current()
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._con)

    def update(self, data: mujoco.MjData, camera_id: int, shadows: bool | None = None) -> None:
        """Place the scene's geoms for `data` as seen from a model camera; shadows and reflections as
        the renderer was made (`shadows`) unless turned off here."""
        if shadows and not self.shadows:
            raise ValueError("shadows: this renderer was made without a shadow map (OffscreenRenderer(shadows=True))")
        shadows = self.shadows if shadows is None else shadows
        self._camera.fixedcamid = camera_id
        mujoco.mjv_updateScene(self.model, data, self._option, None, self._camera,
                               mujoco.mjtCatBit.mjCAT_ALL, self.scene)
        if self.scene.ngeom >= self.scene.maxgeom:     # MuJoCo drops the rest with only a warning
            raise RuntimeError(f"the scene's {self.scene.maxgeom} visual geoms are all used: some would not be "
                               "drawn (pass a larger OffscreenRenderer(max_geom=...))")
        self.scene.flags[_FLAGS.mjRND_SHADOW] = shadows
        self.scene.flags[_FLAGS.mjRND_REFLECTION] = shadows
        self._placement += 1
        self._owners = None
        self._merged = None
        self._camera_id = camera_id

    def color(self) -> np.ndarray:
        """HxWx3 uint8 image of the current scene."""
        self._make_current()
        rgb = np.empty((self.height, self.width, 3), np.uint8)
        merged = self._merged if self._merged is not None and self._merged[0] == self._placement else None
        if merged is not None and self._colour_merge_holds():
            _, welded, not_moving, layer = merged
            if layer.rgb is None:
                layer.rgb = np.empty_like(rgb)
                self._render(colour_pass=True, subset=welded, owners=False)
                mujoco.mjr_readPixels(layer.rgb, None, self._rect, self._con)
            # the layer's pixels wherever no moving geom shows, background included: the skybox then
            # matters to the moving geoms' pass only where it could hide one of them
            flags = self.scene.flags
            sky = bool(flags[_FLAGS.mjRND_SKYBOX])
            if sky and self._skybox_behind(~welded):
                flags[_FLAGS.mjRND_SKYBOX] = False
            try:
                self._render(colour_pass=True, subset=~welded)
            finally:
                flags[_FLAGS.mjRND_SKYBOX] = sky
            mujoco.mjr_readPixels(rgb, None, self._rect, self._con)
            cv2.copyTo(layer.rgb, not_moving.view(np.uint8), rgb)
        else:
            self._render(colour_pass=True)
            mujoco.mjr_readPixels(rgb, None, self._rect, self._con)
        return np.flipud(rgb).copy()

    def _skybox_behind(self, subset: np.ndarray) -> bool:
        """Whether the skybox lies behind every geom of `subset` the colour pass draws, so that it changes
        none of their pixels: mjr_render draws it after the opaque geoms, depth-tested, as a cylinder of
        radius and half-height 0.7 x far about the eye, whose facets come no nearer than cos(pi / slices)
        of that; and no haze (an infinite plane's) is drawn with it."""
        placed = self._geoms[: self.scene.ngeom]
        radius, _, _, planes = self._geom_set(placed)
        size = placed["size"][planes]
        if ((size[:, 0] == 0) & (size[:, 1] == 0)).any():
            return False
        drawn = self._drawn(placed, True)
        drawn = subset if drawn is None else drawn & subset
        cam0, cam1 = self.scene.camera[0], self.scene.camera[1]
        eye = 0.5 * (np.asarray(cam0.pos, np.float64) + np.asarray(cam1.pos, np.float64))
        offset = placed["pos"][drawn] - eye
        room = 0.999 * self._skybox_near * float(cam0.frustum_far) - radius[drawn]    # inf radius: never
        return bool((room > 0).all() and (np.einsum("ij,ij->i", offset, offset) < room * room).all())

    def _colour_merge_holds(self) -> bool:
        """Whether a colour pixel is its owner's colour alone (as for drawing only the pixel owners),
        every geom drawn in colour is in the id pass and no text label is drawn over the scene."""
        view = self._view
        if view is None or view[0] != self._placement or not view[3]:
            return False
        placed = self._geoms[: self.scene.ngeom]
        return bool((placed["segid"] >= 0).all() and not placed["label"][:, 0].any())

    def depth_and_geoms(self, want_geoms: bool) -> tuple[np.ndarray, np.ndarray | None]:
        """Metric depth (HxW float32, far clip where nothing is hit) and, if asked, the geom id per
        pixel (HxW int32, -1 for background and non-geom elements), from one segmentation pass."""
        depth, segments = self.decode(*self.id_pass(want_geoms))
        return depth, (None if segments is None else segments.geom_ids())

    def id_pass(self, want_geoms: bool) -> tuple[np.ndarray, np.ndarray | None]:
        """The GL work of `depth_and_geoms`: render the segmentation pass and read back its depth
        buffer and (if asked) segment colours, bottom row first; `decode` turns them into images.
        Rendered before `color()` of the same placement, it also tells that colour pass which geoms
        own a pixel."""
        self._make_current()
        layer, welded = self._still_layer()        # before the flags change: they are part of its key
        flags = self.scene.flags
        saved = flags.copy()
        flags[_FLAGS.mjRND_SEGMENT] = True
        flags[_FLAGS.mjRND_IDCOLOR] = True
        track = self._geoms is not None
        colours = np.empty((self.height, self.width, 3), np.uint8) if want_geoms or track else None
        depth = np.empty((self.height, self.width), np.float32)
        try:
            if layer is None:
                self._render(colour_pass=False)
                mujoco.mjr_readPixels(colours, depth, self._rect, self._con)
            else:
                if layer.ids is None:
                    layer.ids = (np.empty_like(depth), np.empty_like(colours))
                    self._render(colour_pass=False, subset=welded)
                    mujoco.mjr_readPixels(layer.ids[1], layer.ids[0], self._rect, self._con)
                self._render(colour_pass=False, subset=~welded)
                mujoco.mjr_readPixels(colours, depth, self._rect, self._con)
                placed = self._geoms[: self.scene.ngeom]
                draw_order = np.full(int(placed["segid"].max(initial=-1)) + 2, -1, np.int64)
                draw_order[placed["segid"] + 1] = np.arange(len(placed))      # segid >= 0: see _still_layer
                depth, colours, not_moving = merge_id_passes(layer.ids, (depth, colours), draw_order,
                                                              self.scene.ngeom)
                self._merged = (self._placement, welded, not_moving, layer)
        finally:
            np.copyto(flags, saved)
        if track:
            self._owners = (self._placement, self._owning_segids(colours))
        return depth, (colours if want_geoms else None)

    def _still_layer(self) -> tuple[Layer | None, np.ndarray | None]:
        """For a still camera, its kept passes of the welded geoms (made or remade when their key changed:
        then the camera is rendered whole this once) and which placed geoms are welded; else (None, None).
        Only where merging two passes by depth gives the whole pass's bytes: no multisampling, stereo,
        scene transform or frame border, every placed geom in the id pass."""
        n = self.scene.ngeom
        if self._camera_id not in self._still_cameras or self._geoms is None or n == 0 or self._con.offSamples \
                or self.scene.stereo or self.scene.enabletransform or self.scene.framewidth:
            return None, None
        placed = self._geoms[:n]
        # which placed geoms are welded: the same list of objects as the last placement (the usual case)
        # gives the same answer
        objects = placed[["objtype", "objid", "segid"]].tobytes()
        if self._welded_placed is None or self._welded_placed[0] != objects:
            ids = np.clip(placed["objid"], 0, len(self._welded_geom) - 1)     # other objects' ids: any
            welded = (placed["objtype"] == _OBJ_GEOM) & self._welded_geom[ids]
            usable = welded.any() and not (placed["segid"] < 0).any()
            self._welded_placed = (objects, welded if usable else None)
        welded = self._welded_placed[1]
        if welded is None:
            return None, None
        key = self._view_key() + self._records[:n][welded].tobytes()
        layer = self._layers.get(self._camera_id)
        if layer is None or layer.key != key:
            self._layers[self._camera_id] = Layer(key)      # seen once: kept from the next placement on
            return None, None
        return layer, welded

    def _render(self, colour_pass: bool, subset: np.ndarray | None = None, owners: bool = True) -> None:
        """mjr_render of the geoms that can reach a pixel (all of them without a geom view), of `subset`
        only if given (placed geoms), without drawing only the id pass's pixel owners if `owners` is
        False; the scene is left as it was."""
        n = self.scene.ngeom
        keep = None if self._geoms is None or n == 0 else self._drawn(self._geoms[:n], colour_pass and owners)
        if subset is not None:
            keep = subset if keep is None else keep & subset
        if keep is None or keep.all():
            mujoco.mjr_render(self._rect, self.scene, self._con)
            return
        records = self._records               # the same buffer as raw bytes: plain row copies
        placed = records[:n].copy()
        try:
            kept = placed[keep]
            records[:len(kept)] = kept
            self.scene.ngeom = len(kept)
            mujoco.mjr_render(self._rect, self.scene, self._con)
        finally:
            records[:n] = placed    # also undoes what mjr_render writes into geoms (camdist, flags)
            self.scene.ngeom = n

    def _drawn(self, geoms: np.ndarray, colour_pass: bool) -> np.ndarray | None:
        """Which placed geoms to draw (None: all). The view test is made once per placement."""
        if self._view is None or self._view[0] != self._placement:
            self._view = (self._placement, *self._frustum(geoms))
        _, keep, always, owners_apply = self._view
        if keep is None or not colour_pass or not owners_apply or self._owners is None \
                or self._owners[0] != self._placement:
            return keep
        segid, owners = geoms["segid"], self._owners[1]
        if segid.max() >= len(owners):
            return keep      # a segment id the id pass cannot have told apart: no pixel owners
        owns = segid < 0     # not drawn in the id pass: always drawn
        owns[~owns] = owners[segid[~owns]]
        return keep & (owns | always)

    def _frustum(self, geoms: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None, bool]:
        """(placed geoms whose bounding sphere reaches the camera's view frustum, geoms that are always
        drawn, whether a colour pass may draw only the id pass's pixel owners) - (None, None, False):
        draw all."""
        scene, flags = self.scene, self.scene.flags
        if scene.stereo or scene.enabletransform or flags[_FLAGS.mjRND_SHADOW] or flags[_FLAGS.mjRND_REFLECTION]:
            return None, None, False     # shadows and reflections show geoms from outside the view
        cam0, cam1 = scene.camera[0], scene.camera[1]
        if cam0.orthographic:
            return None, None, False
        radius, always, opaque, planes = self._geom_set(geoms)
        apex = 0.5 * (np.asarray(cam0.pos, np.float64) + np.asarray(cam1.pos, np.float64))
        (fx, fy, fz), (ux, uy, uz) = cam0.forward.tolist(), cam0.up.tolist()    # plain floats: small
        right = (fy * uz - fz * uy, fz * ux - fx * uz, fx * uy - fy * ux)     # numpy calls cost more here
        near, top, bottom = float(cam0.frustum_near), float(cam0.frustum_top), float(cam0.frustum_bottom)
        half = float(cam0.frustum_width) or 0.5 * self.width / self.height * (top - bottom)   # as mjr_render
        left, right_edge = float(cam0.frustum_center) - half, float(cam0.frustum_center) + half
        # inward unit normals in the camera frame (x right, y up, z forward): the near plane, then the
        # side planes through the apex; as world directions, one matrix product tests every geom
        planes_cam = [(0.0, 0.0, 1.0), (near, 0.0, -left), (-near, 0.0, right_edge), (0.0, near, -bottom),
                      (0.0, -near, top)]
        rx, ry, rz = right
        normals = []
        for a, b, c in planes_cam:
            h = math.hypot(a, b, c)
            normals.append(((a * rx + b * ux + c * fx) / h, (a * ry + b * uy + c * fy) / h,
                            (a * rz + b * uz + c * fz) / h))
        distance = (geoms["pos"] - apex) @ np.array(normals).T
        distance[:, 0] -= near
        # (a pose gone NaN is drawn, as it was before culling)
        keep = ~(distance <= -radius[:, None]).any(axis=1) | always
        # a plane seen from (almost) behind is drawn as transparent by mjr_render
        behind = False
        for i in planes:
            mat, pos = geoms["mat"][i].tolist(), geoms["pos"][i].tolist()
            behind |= sum((apex[k] - pos[k]) * mat[2 + 3 * k] for k in range(3)) < 1e-6
        owners_apply = opaque and not behind and not self._con.offSamples and not flags[_FLAGS.mjRND_WIREFRAME]
        return keep, always, owners_apply

    def _geom_set(self, geoms: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool, np.ndarray]:
        """What does not change with the pose, kept while the placed geoms' types, sizes, labels,
        alphas and reflectances stay the same: bounding radii, the geoms always drawn (unbounded
        types, text labels), whether all are opaque (no transparency, no reflective geom: the colour
        pass's pixel owners are then the id pass's) and the rows of planes."""
        label = geoms["label"][:, 0]
        key = b"".join(geoms[f].tobytes() for f in ("type", "size", "modelrbound", "rgba", "reflectance")) \
            + label.tobytes()
        if self._set is None or self._set[0] != key:
            kind = geoms["type"]
            radius = _bounding_radii(geoms)
            always = ~np.isfinite(radius) | (label != 0)
            flat = (kind == _PLANE) | (kind == _BOX)
            opaque = not ((geoms["rgba"][:, 3] < _OPAQUE_ALPHA).any() or ((geoms["reflectance"] > 0) & flat).any())
            self._set = (key, radius, always, opaque, np.flatnonzero(kind == _PLANE))
        return self._set[1:]

    def _owning_segids(self, colours: np.ndarray) -> np.ndarray:
        """[segid] -> owns a pixel of this id pass, from its colours (segid + 1 packed, 0 = none)."""
        n = self.scene.ngeom
        if n < 255:
            counts = cv2.calcHist([colours], [0], None, [256], [0, 256]).ravel()    # channel 0
        else:
            index = (colours[..., 0].astype(np.int64) | colours[..., 1].astype(np.int64) << 8
                     | colours[..., 2].astype(np.int64) << 16)
            counts = np.bincount(index.ravel(), minlength=n + 1)
        return counts[1:] > 0

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
        if self._geoms is not None:
            placed = self._geoms[:ngeom]
            mine = (placed["segid"] >= 0) & (placed["objtype"] == _OBJ_GEOM)
            lookup[placed["segid"][mine] + 1] = placed["objid"][mine]
        else:
            for g in self.scene.geoms[:ngeom]:
                if g.segid >= 0 and g.objtype == mujoco.mjtObj.mjOBJ_GEOM:
                    lookup[g.segid + 1] = g.objid
        return SegmentIds(index, lookup)

    def close(self) -> None:
        if self._con is not None:
            self._finalizer()
            self._con = None
            self._geoms = None
