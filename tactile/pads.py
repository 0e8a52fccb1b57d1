"""Contact-pad surface meshes built from the declarative pad description carried by hand files.

A pad (attach-body frame, metres)::

    pad:
      center: [0, 0.008, 0.02]   # pad centre, on the contact surface
      normal: [0, 1, 0]          # outward unit normal at the centre (towards objects)
      axis: [0, 0, 1]            # unit vector along the finger (pad length direction)
      length: 0.03               # along axis
      width: 0.018               # across axis
      curvature_radius: 0.009    # cylindrical rounding across the width; 0 = flat

The pad type, its frame and profile and its one parser live with the hand description
(``sim.embodiment.description.TactilePad``), which reads the hand file's ``tactile`` block once;
``parse_pad`` is that parser raising the tactile layer's error.
"""

from __future__ import annotations

import math

import numpy as np
import trimesh

from sim.embodiment.description import TactilePad as PadSpec
from sim.embodiment.description import parse_tactile_pad
from tactile.errors import TactileSpecError

__all__ = ["PadSpec", "build_pad_mesh", "parse_pad"]

MAX_SAGITTA_M = 5e-7  # facet error of the rounded profile (one tenth of a fine quantizer level)


def parse_pad(raw, source=None, field: str = "pad") -> PadSpec:
    """Validate one ``pad`` mapping; errors name ``source`` and the dotted field path."""
    return parse_tactile_pad(raw, source, field, TactileSpecError)


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
