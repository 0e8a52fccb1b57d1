"""The occupancy grid's layout, shared by the sensor-profile parser and the labeler (numpy only).

`shape` = (X, Y, Z) voxels of edge `voxel_size` covering `bounds` = [[x0, y0, z0], [x1, y1, z1]] in
the world frame; voxel [i, j, k] has its centre at bounds[0] + (i + 0.5, j + 0.5, k + 0.5) * voxel.
"""

from __future__ import annotations

import numpy as np

MAX_VOXELS = 64_000_000


def grid_shape(bounds, voxel_size: float) -> tuple[int, int, int]:
    """Voxels per axis; the bounds must span a whole number of voxels on every axis."""
    bounds = np.asarray(bounds, float)
    if bounds.shape != (2, 3) or not np.all(bounds[1] > bounds[0]):
        raise ValueError(f"occupancy bounds: expected [[x0, y0, z0], [x1, y1, z1]] with x0 < x1, y0 < y1, z0 < z1, "
                         f"got {bounds.tolist()}")
    if not voxel_size > 0:
        raise ValueError(f"occupancy voxel size: expected a positive length (m), got {voxel_size}")
    cells = (bounds[1] - bounds[0]) / voxel_size
    shape = np.rint(cells)
    if np.any(np.abs(cells - shape) > 1e-6):
        raise ValueError(f"occupancy bounds {bounds.tolist()}: each extent must be a whole number of "
                         f"{voxel_size} m voxels, got {cells.round(4).tolist()}")
    if np.prod(shape) > MAX_VOXELS:
        raise ValueError(f"occupancy grid {shape.astype(int).tolist()} has more than {MAX_VOXELS} voxels")
    return tuple(int(s) for s in shape)
