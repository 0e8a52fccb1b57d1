"""Schema of `sim/catalog/sensor_profiles/<name>.yaml`: what is rendered, at which resolution and rate."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, field_validator, model_validator

from .base import Bool, CatalogModel, Int, Name, Number, PositiveInt, Str, ranged
from .embodiment import CAMERA_NAMES

# the physics steps at 60 Hz and a frame is taken every 60 / rate steps (episodes.stages.frame_steps)
CONTROL_HZ = 60
Modality = Literal["rgb", "depth", "segmentation", "box2d", "box3d", "occupancy"]
# the table workspace: 1.2 x 0.8 m tables, tops at 0.70 - 0.80 m, objects up to ~0.45 m tall
DEFAULT_OCCUPANCY_BOUNDS_M = ((-0.6, -0.4, 0.65), (0.6, 0.4, 1.25))
DEFAULT_OCCUPANCY_VOXEL_M = 0.02
TessellationCount = Annotated[Int, Field(ge=3, le=128)]


class CamerasBlock(CatalogModel):
    ids: list[Literal[CAMERA_NAMES]] = Field(min_length=1)
    width: PositiveInt = Field(le=8192)
    height: PositiveInt = Field(le=8192)
    modalities: list[Modality] | None = None
    shadows: Bool = False
    antialias: Bool = False
    clip_near_m: Number = ranged(0.01, gt=0, le=10, unit="m")
    clip_far_m: Number = ranged(5.0, gt=0, le=1000, unit="m")       # a table scene: metres, not kilometres
    # (slices, stacks) of MuJoCo's tessellated primitives
    tessellation: Annotated[list[TessellationCount], Field(min_length=2, max_length=2)] | None = None

    @field_validator("ids")
    @classmethod
    def _unique(cls, ids: list[str]) -> list[str]:
        dup = sorted({i for i in ids if ids.count(i) > 1})
        if dup:         # found at load time, not after rendering every frame twice
            raise ValueError(f"camera ids listed once each (repeated: {dup})")
        return ids

    @model_validator(mode="after")
    def _clip_order(self):
        if not self.clip_near_m < self.clip_far_m:
            raise ValueError("clip_near_m below clip_far_m")
        return self


class TactileBlock(CatalogModel):
    enabled: Bool = False
    resolution: PositiveInt = Field(240, le=4096)
    step: PositiveInt = 1
    max_range_mm: Number = ranged(15.0, gt=0, le=1000, unit="mm")

    @model_validator(mode="after")
    def _step_fits(self):
        if self.step > self.resolution:
            raise ValueError(f"step at most resolution ({self.resolution})")
        return self


class OccupancyBlock(CatalogModel):
    """World bounds [[x0, y0, z0], [x1, y1, z1]] (m) spanning whole voxels of edge `voxel_size_m`."""

    bounds_m: list[list[Number]] = [list(r) for r in DEFAULT_OCCUPANCY_BOUNDS_M]
    voxel_size_m: Number = Field(DEFAULT_OCCUPANCY_VOXEL_M, gt=0, description="a positive length in metres")

    @field_validator("bounds_m", mode="before")
    @classmethod
    def _two_corners(cls, bounds):
        corners = isinstance(bounds, list) and len(bounds) == 2 and all(
            isinstance(row, list) and len(row) == 3 for row in bounds)
        if not corners:
            raise ValueError("[[x0, y0, z0], [x1, y1, z1]] in metres")
        return bounds

    @model_validator(mode="after")
    def _whole_voxels(self):
        from sim.labels.grid import grid_shape      # numpy only

        shape = grid_shape(self.bounds_m, self.voxel_size_m)   # its ValueError names the bounds and the voxel
        if min(shape) < 1:
            raise ValueError(f"a voxel_size_m no larger than the bounds' smallest extent (grid {list(shape)})")
        return self


class SensorProfileFile(CatalogModel):
    name: Name
    description: Str = ""
    rate_hz: Int = Field(ge=1, le=CONTROL_HZ)
    cameras: CamerasBlock
    tactile: TactileBlock = TactileBlock()
    occupancy: OccupancyBlock = OccupancyBlock()

    @field_validator("rate_hz")
    @classmethod
    def _divides_control_rate(cls, rate: int) -> int:
        if CONTROL_HZ % rate:
            raise ValueError(f"a rate dividing the control rate {CONTROL_HZ} Hz (1, 2, 3, 4, 5, 6, 10, 12, 15, 20, "
                             f"30 or 60)")
        return rate
