"""Schema of `sim/catalog/tasks/<name>.yaml`: the table, the objects and where they start, zones and points.

An object's geometry and joints (`shape` + `size`, `parts`, `links`, `key_rows`) are checked by the models
in sim/schema/object_parts.py; a mesh's file where it is read (sim/scene/mesh_files.py). Blocks with their
own compilers stay mappings or lists here and are checked by them, with the same file-and-field errors:
`demo_plan` (sim/demo_plan.py, which validates each step against its kind's schema in
sim/schema/demo_plan/, with the task's objects as context) and `metrics` (the shared evaluator). What
refers across objects (a zone, a support object, the paper embodiment) is checked by the loader."""

from __future__ import annotations

from typing import Annotated, Any, ClassVar, Literal

from pydantic import Field, field_validator, model_validator

from .base import Bool, CatalogModel, Name, Number, PositiveNumber, Str, Vec3, ranged
from .object_parts import (DENSITY_RANGE_KG_M3, FRICTION_RANGE, MASS_RANGE_KG, ROLLING_FRICTION_RANGE_M, SHAPES, KeyRow,
                           Link, PartEntry, Sizes, shape_size, unique_link_names)
from .robot_parts import SPAN_M, Coord, Length, Point3, Rgba

TABLE_HEIGHT_RANGE_M = (0.4, 1.2)
TABLE_THICKNESS_RANGE_M = (0.01, 0.2)
BASES = ("free", "fixed")          # fixed: the base is part of the world (fridge, toilet, piano)
GEOMETRY_KEYS = ("shape", "parts", "mesh")     # exactly one ("size" goes with "shape")
TableXY = Annotated[list[Coord], Field(min_length=2, max_length=2)]     # table-relative [x, y] (m)


class Table(CatalogModel):
    height: Number = ranged(0.75, ge=TABLE_HEIGHT_RANGE_M[0], le=TABLE_HEIGHT_RANGE_M[1], unit="m")
    size_xy: Annotated[list[PositiveNumber], Field(min_length=2, max_length=2)] = [1.2, 0.8]
    thickness: Number = ranged(0.04, ge=TABLE_THICKNESS_RANGE_M[0], le=TABLE_THICKNESS_RANGE_M[1], unit="m")
    friction: Number = ranged(0.8, ge=FRICTION_RANGE[0], le=FRICTION_RANGE[1])


class Zone(CatalogModel):
    """A placement zone on the table: a rectangle {xy_min, xy_max} or a disc {center_xy, radius}."""

    xy_min: TableXY | None = None
    xy_max: TableXY | None = None
    center_xy: TableXY | None = None
    radius: Number | None = ranged(None, gt=0.0, le=SPAN_M, unit="m")

    @model_validator(mode="after")
    def _one_shape(self):
        given = {k for k in ("xy_min", "xy_max", "center_xy", "radius") if getattr(self, k) is not None}
        if given not in ({"xy_min", "xy_max"}, {"center_xy", "radius"}):
            raise ValueError("{xy_min: [x, y], xy_max: [x, y]} or {center_xy: [x, y], radius: r}")
        if self.xy_min is not None and not all(a < b for a, b in zip(self.xy_min, self.xy_max)):
            raise ValueError("xy_min below xy_max on both axes")
        return self


class Pose(CatalogModel):
    keys_label: ClassVar[str] = "a pose key"

    xy: TableXY                    # table-relative, or in the support object's frame
    yaw_deg: Number = ranged(0.0, ge=-360, le=360, unit="degrees")
    support: Name | None = None    # starts standing on this earlier object ("on" is a YAML boolean)


class Container(CatalogModel):
    interior_half_extents: Annotated[list[Length], Field(min_length=3, max_length=3)]
    interior_offset: Point3 = [0.0, 0.0, 0.0]


class TaskObject(CatalogModel):
    keys_label: ClassVar[str] = "an object key"

    shape: Literal[SHAPES] = None      # shape + size (one primitive), mesh or parts: sim/scene/parts.py
    size: Sizes = None
    parts: list[PartEntry] = Field(None, min_length=1)
    mesh: Any = None                   # a file path or {file, scale}: sim/scene/mesh_files.py
    mass: Number | None = ranged(None, ge=MASS_RANGE_KG[0], le=MASS_RANGE_KG[1], unit="kg")
    density: Number | None = ranged(None, ge=DENSITY_RANGE_KG_M3[0], le=DENSITY_RANGE_KG_M3[1], unit="kg/m^3")
    friction: Number = ranged(1.0, ge=FRICTION_RANGE[0], le=FRICTION_RANGE[1])
    rolling_friction: Number = ranged(0.0, ge=ROLLING_FRICTION_RANGE_M[0], le=ROLLING_FRICTION_RANGE_M[1], unit="m")
    rgba: Rgba = [0.7, 0.7, 0.7, 1.0]
    pose: Pose | None = Field(None, description="a mapping {xy, yaw_deg}")
    zone: Name | None = None
    fixed_pose: Bool = False           # task constraint: never perturbed
    container: Container | None = Field(None, description="a mapping {interior_half_extents, interior_offset}")
    base: Literal[BASES] = "free"
    links: dict[str, Link] = None      # articulated links: sim/scene/articulated.py
    key_rows: list[KeyRow] = None
    mouth_axis: Vec3 | None = None     # pourers: local axis of the mouth

    _size = field_validator("size")(shape_size)

    @model_validator(mode="after")
    def _one_of_each(self):
        given = [k for k in GEOMETRY_KEYS if getattr(self, k) is not None]
        if len(given) != 1 or (self.size is not None) != (self.shape is not None):
            raise ValueError("exactly one of 'shape' with 'size' (one primitive), 'mesh' (a mesh file) or 'parts'")
        if (self.pose is None) == (self.zone is None):
            raise ValueError("exactly one of 'pose' or 'zone'")
        if self.mass is not None and self.density is not None:
            raise ValueError("one of 'mass' (kg) or 'density' (kg/m^3), not both")
        unique_link_names(self.links, self.key_rows)
        return self


class TaskFile(CatalogModel):
    name: Name
    display_name: Str | None = None
    instruction: Str
    success_condition: Str = ""
    paper_embodiment: Str = ""
    table: Table | None = Field(None, description="a mapping {height, size_xy, thickness, friction}")
    objects: dict[str, TaskObject] = Field(min_length=1, description="a mapping of object name -> object")
    zones: dict[str, Zone] | None = Field(None, description="a mapping of zone name -> zone")
    points: dict[str, Point3] | None = Field(None, description="a mapping of point name -> [x, y, z]")
    demo_plan: Any = None              # sim/demo_plan.py
    demo_plan_draft: Bool = Field(False, description="true or false (true: the plan does not reach stable success "
                                  "yet; `b2d bench demos --setting KEY` runs it, the setting is not recordable)")
    metrics: dict = Field(description="a mapping: the metrics block")
