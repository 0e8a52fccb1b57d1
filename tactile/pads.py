"""Contact-pad surface meshes built from the declarative pad description carried by hand files.

A pad (attach-body frame, metres)::

    pad:
      center: [0, 0.008, 0.02]   # pad centre, on the contact surface
      normal: [0, 1, 0]          # outward unit normal at the centre (towards objects)
      axis: [0, 0, 1]            # unit vector along the finger (pad length direction)
      length: 0.03               # along axis
      width: 0.018               # across axis
      curvature_radius: 0.009    # cylindrical rounding across the width; 0 = flat

Pad frame: origin ``center``; ``e_width = axis x normal``, ``e_axis = axis``, ``e_normal = normal``
(right-handed). The surface is the sheet ``h(x)`` over ``|x| <= width/2`` (x along e_width), straight
along the axis. With radius R > 0: ``a = max(0, width/2 - R)``, ``t = max(0, |x| - a)``,
``h = sqrt(R^2 - t^2) - R``: a circular arc for R >= width/2, a flat middle with rounded edges of
radius R otherwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import trimesh

from tactile.errors import TactileSpecError

PAD_FIELDS = ("center", "normal", "axis", "length", "width", "curvature_radius")
UNIT_TOLERANCE = 1e-3
ORTHOGONAL_TOLERANCE = 1e-3
MAX_SAGITTA_M = 5e-7  # facet error of the rounded profile (one tenth of a fine quantizer level)


@dataclass(frozen=True)
class PadSpec:
    center: tuple[float, float, float]
    normal: tuple[float, float, float]
    axis: tuple[float, float, float]
    length: float
    width: float
    curvature_radius: float = 0.0

    def frame(self) -> np.ndarray:
        """3x3 rotation whose columns are e_width, e_axis, e_normal (attach-body frame)."""
        n = np.asarray(self.normal, dtype=np.float64)
        a = np.asarray(self.axis, dtype=np.float64)
        return np.column_stack([np.cross(a, n), a, n])

    def profile(self, x: np.ndarray) -> np.ndarray:
        """Surface height h(x) <= 0 below the centre plane, x across the width (metres)."""
        r = self.curvature_radius
        if r == 0:
            return np.zeros_like(x, dtype=np.float64)
        t = np.maximum(0.0, np.abs(x) - max(0.0, self.width / 2 - r))
        return np.sqrt(np.maximum(r * r - t * t, 0.0)) - r


def _vector(raw: dict, key: str, source, prefix: str) -> np.ndarray:
    value = raw.get(key)
    try:
        vec = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        vec = None
    if vec is None or vec.shape != (3,) or not np.all(np.isfinite(vec)):
        raise TactileSpecError(source, f"{prefix}{key}", "a list of 3 finite numbers", value)
    return vec


def _length(raw: dict, key: str, source, prefix: str, allow_zero: bool = False) -> float:
    value = raw.get(key)
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or value < 0 or (value == 0 and not allow_zero):
        what = "a number >= 0 (metres)" if allow_zero else "a positive number (metres)"
        raise TactileSpecError(source, f"{prefix}{key}", what, value)
    return float(value)


def parse_pad(raw, source=None, field: str = "pad") -> PadSpec:
    """Validate one ``pad`` mapping; errors name ``source`` and the dotted field path."""
    if not isinstance(raw, dict):
        raise TactileSpecError(source, field, "a mapping with " + ", ".join(PAD_FIELDS), raw)
    prefix = f"{field}."
    missing = [k for k in PAD_FIELDS if k not in raw and k != "curvature_radius"]
    if missing:
        raise TactileSpecError(source, prefix + missing[0], "a value (field is missing)")
    unknown = sorted(set(raw) - set(PAD_FIELDS))
    if unknown:
        raise TactileSpecError(source, prefix + unknown[0], "one of " + ", ".join(PAD_FIELDS), "unknown")
    center = _vector(raw, "center", source, prefix)
    normal = _vector(raw, "normal", source, prefix)
    axis = _vector(raw, "axis", source, prefix)
    for key, vec in (("normal", normal), ("axis", axis)):
        if abs(np.linalg.norm(vec) - 1.0) > UNIT_TOLERANCE:
            raise TactileSpecError(source, prefix + key, "a unit vector", vec.tolist())
    if abs(float(normal @ axis)) > ORTHOGONAL_TOLERANCE:
        raise TactileSpecError(source, prefix + "axis", "a vector orthogonal to normal", axis.tolist())
    normal = normal / np.linalg.norm(normal)
    axis = axis - (axis @ normal) * normal
    axis = axis / np.linalg.norm(axis)
    raw_radius = raw.get("curvature_radius", 0.0)
    return PadSpec(
        center=tuple(float(v) for v in center),
        normal=tuple(float(v) for v in normal),
        axis=tuple(float(v) for v in axis),
        length=_length(raw, "length", source, prefix),
        width=_length(raw, "width", source, prefix),
        curvature_radius=_length({"curvature_radius": raw_radius}, "curvature_radius", source, prefix, True),
    )


def _profile_samples(pad: PadSpec) -> np.ndarray:
    """Across-width sample positions: two for a flat pad, dense enough on the rounded parts."""
    half = pad.width / 2
    r = pad.curvature_radius
    if r == 0:
        return np.array([-half, half])
    flat = max(0.0, half - r)
    sweep = math.asin(min(1.0, (half - flat) / r))  # arc angle of each rounded side
    max_step = 2 * math.acos(1 - MAX_SAGITTA_M / r)
    n = max(2, math.ceil(sweep / max_step))
    angles = np.linspace(0.0, sweep, n + 1)
    side = flat + r * np.sin(angles)
    xs = np.concatenate([-side[::-1], side[1:]] if flat == 0 else [-side[::-1], side])
    return np.unique(xs)


def build_pad_mesh(pad: PadSpec) -> trimesh.Trimesh:
    """Open contact-surface sheet of the pad in the attach-body frame (face normals outward)."""
    xs = _profile_samples(pad)
    hs = pad.profile(xs)
    ys = np.array([-pad.length / 2, pad.length / 2])
    local = np.array([[x, y, h] for y in ys for x, h in zip(xs, hs)])
    frame = pad.frame()
    vertices = local @ frame.T + np.asarray(pad.center)
    m = len(xs)
    faces = []
    for i in range(m - 1):  # (x_i, y0), (x_i+1, y0), (x_i+1, y1), (x_i, y1): counter-clockwise seen from +normal
        a, b, c, d = i, i + 1, m + i + 1, m + i
        faces += [[a, b, c], [a, c, d]]
    return trimesh.Trimesh(vertices=vertices, faces=np.array(faces), process=False)
