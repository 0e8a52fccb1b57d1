"""Task descriptions loaded from `sim/catalog/tasks/<name>.yaml`.

A task declares its table, its objects (primitives and generated shapes built by b2d, or mesh
files; fixed or free, with articulated links), where they start (a pose or a placement zone), an
optional scripted demonstration plan (sim/demo_plan.py) and its `metrics` block, which the shared
evaluator compiles at load time. No task needs Python of its own. Masses, frictions and densities are range-checked
(`sim.scene.fields`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from sim.demo_plan import PlanScope, parse_plan
from sim.errors import SpecError
from evaluation import EpisodeEvaluator, TaskContext, TaskSpecError
from evaluation.state import ObjectInfo
from sim.registry import catalog_path, load_yaml, names
from sim.scene.articulated import LinkSpec, parse_links
from sim.scene.fields import (DENSITY_RANGE_KG_M3, FRICTION_RANGE, MASS_RANGE_KG, ROLLING_FRICTION_RANGE_M,
                              num_list, number)
from sim.scene.parts import Cavity, Part, parse_part, parse_parts, parts_aabb

DEFAULT_TABLE_HEIGHT = 0.75
DEFAULT_MASS_KG = 0.1
OBJECT_KEYS = ("shape", "size", "parts", "mesh", "mass", "density", "friction", "rolling_friction", "rgba", "pose",
               "zone", "fixed_pose", "container", "base", "links", "key_rows", "mouth_axis")
GEOMETRY_KEYS = ("shape", "parts", "mesh")     # exactly one ("size" goes with "shape")
BASES = ("free", "fixed")          # fixed: the base is part of the world (fridge, toilet, piano)
CENTRE_TOLERANCE_M = 0.005
TABLE_HEIGHT_RANGE_M = (0.4, 1.2)
TABLE_THICKNESS_RANGE_M = (0.01, 0.2)


@dataclass(frozen=True)
class ObjectSpec:
    name: str
    mass: float
    friction: float
    rgba: tuple[float, float, float, float]
    xy: tuple[float, float] | None        # nominal table-relative position, or None when zoned
    yaw_deg: float
    zone: str | None
    fixed_pose: bool                      # task constraint: never perturbed
    interior_half_extents: tuple[float, float, float] | None = None
    interior_offset: tuple[float, float, float] | None = None
    rolling_friction: float = 0.0         # metres; > 0 resists rolling (soft, not perfectly round objects)
    parts: tuple[Part, ...] = ()          # the base body's primitives, in the object frame
    links: tuple[LinkSpec, ...] = ()      # articulated links (joints "<name>/<link>")
    base: str = "free"
    mouth_axis: tuple[float, float, float] | None = None   # pourers: local axis of the mouth
    on: str | None = None                 # pose.support: starts on this object, xy/yaw in its frame

    @property
    def support_height(self) -> float:
        """Height, in the object frame, of what an object put `on` it stands on: the cavity floor of
        a container, else the top of its box."""
        if self.interior_half_extents is not None:
            return float(self.interior_offset[2] - self.interior_half_extents[2])
        return float(self.half_extents[2])

    @property
    def half_extents(self) -> np.ndarray:
        """Half sizes of the base's bounding box around the object frame (the evaluator's box)."""
        lo, hi = parts_aabb(self.parts)
        return (hi - lo) / 2

    @property
    def rest_height(self) -> float:
        """Height of the object frame above its support when upright (links at joint zero included)."""
        return float(-self._aabb_all()[0][2])

    @property
    def footprint_radius(self) -> float:
        """Radius of the object's xy footprint, links included, for collision-free placement."""
        lo, hi = self._aabb_all()
        return float(np.hypot(*np.maximum(-lo[:2], hi[:2])))

    def _aabb_all(self) -> tuple[np.ndarray, np.ndarray]:
        boxes = [parts_aabb(self.parts)] + [parts_aabb(l.parts, l.pos, l.quat) for l in self.links]
        return np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0)

    @property
    def joint_names(self) -> list[str]:
        return [f"{self.name}/{link.name}" for link in self.links]


@dataclass(frozen=True)
class TableSpec:
    height: float
    size_xy: tuple[float, float]
    thickness: float
    friction: float


@dataclass(frozen=True)
class TaskSpec:
    name: str
    display_name: str
    instruction: str
    success_condition: str
    paper_embodiment: str
    table: TableSpec
    objects: dict[str, ObjectSpec]
    zones: dict[str, dict]
    points: dict[str, list]
    demo_plan: list[dict]
    metrics: dict
    source: Path
    raw: dict = field(repr=False, default_factory=dict)


    @property
    def joint_names(self) -> list[str]:
        """Every articulated joint, "<object>/<link>", as the evaluator names them."""
        return [j for o in self.objects.values() for j in o.joint_names]


def _geometry(path, where, raw) -> tuple[tuple[Part, ...], Cavity | None]:
    """shape + size (one primitive), mesh (one mesh file) or parts (primitives, generated shapes
    and meshes)."""
    given = [k for k in GEOMETRY_KEYS if k in raw]
    if len(given) != 1 or ("size" in raw) != ("shape" in raw):
        raise SpecError(path, where, "exactly one of 'shape' with 'size' (one primitive), 'mesh' (a mesh file) "
                        "or 'parts'", sorted(k for k in raw if k in (*GEOMETRY_KEYS, "size")))
    if "parts" in raw:
        return parse_parts(path, f"{where}.parts", raw["parts"])
    if "mesh" in raw:
        parts, _ = parse_part(path, where, {"mesh": raw["mesh"]})
        return tuple(parts), None
    parts, _ = parse_part(path, where, {"shape": raw["shape"], "size": raw["size"]})
    return tuple(parts), None


def _mass(path, where, raw, parts) -> float:
    """The declared mass, or the density times the parts' volume (a mesh part: its hull's)."""
    if "mass" in raw and "density" in raw:
        raise SpecError(path, where, "one of 'mass' (kg) or 'density' (kg/m^3), not both")
    if "density" in raw:
        density = number(path, f"{where}.density", raw["density"], *DENSITY_RANGE_KG_M3, unit="kg/m^3")
        mass = density * sum(p.volume for p in parts)
        low, high = MASS_RANGE_KG
        if not low <= mass <= high:
            raise SpecError(path, f"{where}.density", f"a density giving a mass in [{low}, {high}] kg "
                            f"(this one gives {mass:.4g} kg)", raw["density"])
        return float(mass)
    return number(path, f"{where}.mass", raw.get("mass", DEFAULT_MASS_KG), *MASS_RANGE_KG, unit="kg")


def _parse_object(path, name, raw, zones, earlier) -> ObjectSpec:
    where = f"objects.{name}"
    if not isinstance(raw, dict):
        raise SpecError(path, where, "a mapping", raw)
    for key in raw:
        if key not in OBJECT_KEYS:
            raise SpecError(path, f"{where}.{key}", f"an object key {list(OBJECT_KEYS)}")
    parts, cavity = _geometry(path, where, raw)
    lo, hi = parts_aabb(parts)
    if np.abs((lo + hi) / 2).max() > CENTRE_TOLERANCE_M:
        raise SpecError(path, f"{where}.parts", "parts centred on the object frame (the evaluator's box "
                        f"centre); shift them by {(-(lo + hi) / 2).round(4).tolist()}")
    pose = raw.get("pose")
    zone = raw.get("zone")
    if (pose is None) == (zone is None):
        raise SpecError(path, where, "exactly one of 'pose' or 'zone'")
    if zone is not None and zone not in zones:
        raise SpecError(path, f"{where}.zone", f"a zone from {sorted(zones)}", zone)
    if pose is not None and not isinstance(pose, dict):
        raise SpecError(path, f"{where}.pose", "a mapping {xy, yaw_deg}", pose)
    for key in pose or {}:
        if key not in ("xy", "yaw_deg", "support"):
            raise SpecError(path, f"{where}.pose.{key}", "a pose key ['xy', 'yaw_deg', 'support']")
    xy = num_list(path, f"{where}.pose.xy", pose.get("xy"), 2) if pose else None
    on = (pose or {}).get("support")      # starts standing on this object ("on" is a YAML boolean)
    if on is not None and on not in earlier:
        raise SpecError(path, f"{where}.pose.support", f"an object declared before {name!r}: {sorted(earlier)}", on)
    if not isinstance(raw.get("fixed_pose", False), bool):
        raise SpecError(path, f"{where}.fixed_pose", "true or false", raw["fixed_pose"])
    base = raw.get("base", "free")
    if base not in BASES:
        raise SpecError(path, f"{where}.base", f"one of {list(BASES)}", base)
    container = raw.get("container")
    if container is not None:
        if not isinstance(container, dict) or "interior_half_extents" not in container:
            raise SpecError(path, f"{where}.container", "a mapping {interior_half_extents, interior_offset}", container)
        interior = num_list(path, f"{where}.container.interior_half_extents", container["interior_half_extents"], 3)
        offset = num_list(path, f"{where}.container.interior_offset", container.get("interior_offset", [0, 0, 0]), 3)
    elif cavity is not None:      # a generated open shape brings its own cavity
        interior, offset = cavity.half_extents, cavity.offset
    else:
        interior = offset = None
    return ObjectSpec(
        name=name,
        mass=_mass(path, where, raw, parts),
        friction=number(path, f"{where}.friction", raw.get("friction", 1.0), *FRICTION_RANGE),
        rgba=num_list(path, f"{where}.rgba", raw.get("rgba", [0.7, 0.7, 0.7, 1.0]), 4),
        xy=xy,
        yaw_deg=number(path, f"{where}.pose.yaw_deg", (pose or {}).get("yaw_deg", 0.0), unit="degrees"),
        zone=zone,
        fixed_pose=raw.get("fixed_pose", False),
        rolling_friction=number(path, f"{where}.rolling_friction", raw.get("rolling_friction", 0.0),
                                *ROLLING_FRICTION_RANGE_M, unit="m"),
        interior_half_extents=interior,
        interior_offset=offset,
        parts=parts,
        links=parse_links(path, where, raw),
        base=base,
        mouth_axis=num_list(path, f"{where}.mouth_axis", raw["mouth_axis"], 3) if "mouth_axis" in raw else None,
        on=on,
    )


def _mapping(path, field: str, value, what: str) -> dict:
    """An optional top-level block: absent is empty, anything but a mapping is an error."""
    value = {} if value is None else value
    if not isinstance(value, dict):
        raise SpecError(path, field, what, value)
    return value


def _parse_zones(path, raw) -> dict[str, dict]:
    zones = _mapping(path, "zones", raw.get("zones"), "a mapping of zone name -> zone")
    for name, zone in zones.items():
        ok = isinstance(zone, dict) and (set(zone) == {"xy_min", "xy_max"} or set(zone) == {"center_xy", "radius"})
        if not ok:
            raise SpecError(path, f"zones.{name}", "{xy_min: [x, y], xy_max: [x, y]} or {center_xy: [x, y], radius: r}",
                            zone)
        for key, value in zone.items():
            if key == "radius":
                number(path, f"zones.{name}.radius", value, 0.0, low_open=True, unit="m")
            else:
                num_list(path, f"zones.{name}.{key}", value, 2)
        if "xy_min" in zone and not all(a < b for a, b in zip(zone["xy_min"], zone["xy_max"])):
            raise SpecError(path, f"zones.{name}", "xy_min below xy_max on both axes", zone)
    return zones


def _parse_points(path, raw) -> dict[str, list]:
    points = _mapping(path, "points", raw.get("points"), "a mapping of point name -> [x, y, z]")
    for name, p in points.items():
        num_list(path, f"points.{name}", p, 3)
    return points


def task_context(task: TaskSpec) -> TaskContext:
    """The evaluator's static view of a task: object boxes and cavities, zones, table-relative
    points and the articulated joints."""
    infos = {}
    for name, obj in task.objects.items():
        arr = lambda v: None if v is None else np.array(v, dtype=float)  # noqa: E731
        infos[name] = ObjectInfo(name=name, half_extents=obj.half_extents,
                                 interior_half_extents=arr(obj.interior_half_extents),
                                 interior_offset=arr(obj.interior_offset), mouth_axis=arr(obj.mouth_axis))
    points = {k: np.asarray(v, dtype=float) for k, v in task.points.items()}
    return TaskContext(objects=infos, zones=task.zones, points=points, table_relative_points=frozenset(points),
                       joints=frozenset(task.joint_names))


def parse_task(raw: dict, path: Path) -> TaskSpec:
    for key in ("name", "instruction", "objects", "metrics"):
        if key not in raw:
            raise SpecError(path, key, "a value")
    if not isinstance(raw["objects"], dict) or not raw["objects"]:
        raise SpecError(path, "objects", "a mapping of object name -> object", raw["objects"])
    zones = _parse_zones(path, raw)
    points = _parse_points(path, raw)
    objects: dict[str, ObjectSpec] = {}
    for n, o in raw["objects"].items():
        objects[n] = _parse_object(path, n, o, zones, dict(objects))
    table = _mapping(path, "table", raw.get("table"), "a mapping {height, size_xy, thickness, friction}")
    embodiment = raw.get("paper_embodiment", "")
    if embodiment and embodiment not in names("embodiments"):
        raise SpecError(path, "paper_embodiment", f"an embodiment from {names('embodiments')}", embodiment)
    task = TaskSpec(
        name=raw["name"],
        display_name=raw.get("display_name", raw["name"]),
        instruction=raw["instruction"],
        success_condition=raw.get("success_condition", ""),
        paper_embodiment=embodiment,
        table=TableSpec(
            height=number(path, "table.height", table.get("height", DEFAULT_TABLE_HEIGHT), *TABLE_HEIGHT_RANGE_M,
                          unit="m"),
            size_xy=num_list(path, "table.size_xy", table.get("size_xy", [1.2, 0.8]), 2, positive=True),
            thickness=number(path, "table.thickness", table.get("thickness", 0.04), *TABLE_THICKNESS_RANGE_M,
                             unit="m"),
            friction=number(path, "table.friction", table.get("friction", 0.8), *FRICTION_RANGE),
        ),
        objects=objects,
        zones=zones,
        points=points,
        demo_plan=parse_plan(path, raw, PlanScope(objects, zones, points)),
        metrics=raw["metrics"],
        source=Path(path),
        raw=raw,
    )
    try:   # compile the metrics block now: a bad predicate, stage graph or name fails at load time
        EpisodeEvaluator(task.metrics, task_context(task), source=str(path))
    except TaskSpecError as err:
        raise SpecError(path, err.field, err.expected, err.got) from err
    return task


@lru_cache(maxsize=64)
def load_task(name: str) -> TaskSpec:
    path = catalog_path("tasks", name, "task")
    return parse_task(load_yaml(path), path)
