"""Rays against a set of MuJoCo geoms: how far the first surface is, as planners measure a container's
wall, a link's face, an opening or a part's thickness."""

from __future__ import annotations

from typing import Iterable

import mujoco
import numpy as np


def body_geoms(model: mujoco.MjModel, body: int) -> range:
    """The geoms of ``body`` itself (not of links attached to it)."""
    return range(model.body_geomadr[body], model.body_geomadr[body] + model.body_geomnum[body])


def nearest_hit(model: mujoco.MjModel, data: mujoco.MjData, geoms: Iterable[int], origin: np.ndarray,
                direction: np.ndarray) -> float | None:
    """Distance along ``direction`` from ``origin`` to the first of ``geoms`` (as posed in ``data``) a ray
    meets, in units of ``direction``'s length; None when it meets none."""
    hits = [mujoco.mju_rayGeom(data.geom_xpos[g], data.geom_xmat[g], model.geom_size[g], origin, direction,
                               int(model.geom_type[g])) for g in geoms]
    hits = [h for h in hits if h >= 0]
    return min(hits) if hits else None
