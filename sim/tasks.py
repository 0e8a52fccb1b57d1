"""Task descriptions loaded from `sim/catalog/tasks/<name>.yaml`.

A task declares its table, its objects (primitives and generated shapes built by b2d, or mesh
files; fixed or free, with articulated links), where they start (a pose or a placement zone), an
optional scripted demonstration plan (sim/demo_plan.py) and its `metrics` block, which the shared
evaluator compiles at load time. No task needs Python of its own. The file's keys, types and ranges
are checked by its schema (`sim.schema.task`; an object's geometry, joints and physical bounds:
`sim.schema.object_parts`); this module builds the objects and checks what refers across them.
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
from sim.registry import Setting, catalog_path, load_yaml, names
from sim.scene.articulated import LinkSpec, build_links
from sim.scene.parts import Cavity, Part, build_part, build_parts, parts_aabb
from sim.schema import validate
from sim.schema.object_parts import MASS_RANGE_KG, PartEntry
from sim.schema.task import TABLE_HEIGHT_RANGE_M, TABLE_THICKNESS_RANGE_M, Table, TaskFile, TaskObject  # noqa: F401

DEFAULT_TABLE_HEIGHT = 0.75      # the schema's default (sim.schema.task.Table)
DEFAULT_MASS_KG = 0.1
CENTRE_TOLERANCE_M = 0.005


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
    demo_plan_draft: bool = False     # a plan without stable success yet: not recordable, benched when named


    @property
    def joint_names(self) -> list[str]:
        """Every articulated joint, "<object>/<link>", as the evaluator names them."""
        return [j for o in self.objects.values() for j in o.joint_names]


def _geometry(path, where, obj: TaskObject) -> tuple[tuple[Part, ...], Cavity | None]:
    """shape + size (one primitive), mesh (one mesh file) or parts (primitives, generated shapes
    and meshes); the schema has checked that exactly one is given."""
    if obj.parts is not None:
        return build_parts(path, f"{where}.parts", obj.parts)
    entry = PartEntry(mesh=obj.mesh) if obj.mesh is not None else PartEntry(shape=obj.shape, size=obj.size)
    parts, _ = build_part(path, where, entry)
    return tuple(parts), None


def _mass(path, where, obj: TaskObject, parts) -> float:
    """The declared mass, or the density times the parts' volume (a mesh part: its hull's)."""
    if obj.density is not None:
        mass = obj.density * sum(p.volume for p in parts)
        low, high = MASS_RANGE_KG
        if not low <= mass <= high:
            raise SpecError(path, f"{where}.density", f"a density giving a mass in [{low}, {high}] kg "
                            f"(this one gives {mass:.4g} kg)", obj.density)
        return float(mass)
    return obj.mass if obj.mass is not None else DEFAULT_MASS_KG


def _parse_object(path, name, obj: TaskObject, zones, earlier) -> ObjectSpec:
    """One object: the schema checked its keys, types and ranges; here its geometry and references."""
    where = f"objects.{name}"
    parts, cavity = _geometry(path, where, obj)
    lo, hi = parts_aabb(parts)
    if np.abs((lo + hi) / 2).max() > CENTRE_TOLERANCE_M:
        raise SpecError(path, f"{where}.parts", "parts centred on the object frame (the evaluator's box "
                        f"centre); shift them by {(-(lo + hi) / 2).round(4).tolist()}")
    pose = obj.pose
    if obj.zone is not None and obj.zone not in zones:
        raise SpecError(path, f"{where}.zone", f"a zone from {sorted(zones)}", obj.zone)
    on = pose.support if pose is not None else None
    if on is not None and on not in earlier:
        raise SpecError(path, f"{where}.pose.support", f"an object declared before {name!r}: {sorted(earlier)}", on)
    if obj.container is not None:
        interior = tuple(obj.container.interior_half_extents)
        offset = tuple(obj.container.interior_offset)
    elif cavity is not None:      # a generated open shape brings its own cavity
        interior, offset = cavity.half_extents, cavity.offset
    else:
        interior = offset = None
    return ObjectSpec(
        name=name,
        mass=_mass(path, where, obj, parts),
        friction=obj.friction,
        rgba=tuple(obj.rgba),
        xy=tuple(pose.xy) if pose is not None else None,
        yaw_deg=pose.yaw_deg if pose is not None else 0.0,
        zone=obj.zone,
        fixed_pose=obj.fixed_pose,
        rolling_friction=obj.rolling_friction,
        interior_half_extents=interior,
        interior_offset=offset,
        parts=parts,
        links=build_links(path, where, obj),
        base=obj.base,
        mouth_axis=tuple(obj.mouth_axis) if obj.mouth_axis is not None else None,
        on=on,
    )


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
    m = validate(TaskFile, raw, path)
    zones = raw.get("zones") or {}
    points = raw.get("points") or {}
    objects: dict[str, ObjectSpec] = {}
    for n, obj in m.objects.items():
        objects[n] = _parse_object(path, n, obj, zones, dict(objects))
    table = m.table or Table()
    embodiment = m.paper_embodiment
    if embodiment and embodiment not in names("embodiments"):
        raise SpecError(path, "paper_embodiment", f"an embodiment from {names('embodiments')}", embodiment)
    task = TaskSpec(
        name=m.name,
        display_name=m.display_name if m.display_name is not None else m.name,
        instruction=m.instruction,
        success_condition=m.success_condition,
        paper_embodiment=embodiment,
        table=TableSpec(height=table.height, size_xy=tuple(table.size_xy), thickness=table.thickness,
                        friction=table.friction),
        objects=objects,
        zones=zones,
        points=points,
        demo_plan=parse_plan(path, raw, PlanScope(objects, zones, points)),
        metrics=raw["metrics"],
        source=Path(path),
        raw=raw,
        demo_plan_draft=m.demo_plan_draft,
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


def has_finished_plan(task: str) -> bool:
    """The task has a demonstration plan for the scripted operator that is not a draft."""
    spec = load_task(task)
    return bool(spec.demo_plan) and not spec.demo_plan_draft


def is_recordable(setting: Setting) -> bool:
    """Available and its task has a finished demonstration plan for the scripted operator. (Here, not on
    `Setting`: the registry stays below the tasks, with no import back.)"""
    return setting.available and has_finished_plan(setting.task)
