"""Task descriptions loaded from `sim/catalog/tasks/<name>.yaml`.

A task declares its table, its objects (primitive shapes built by b2d, or a mesh file), where they
start (a pose or a placement zone), its scripted demonstration plan and its `metrics` block, which
the shared evaluator compiles. No task needs Python of its own.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from sim.errors import SpecError
from sim.registry import catalog_path, load_yaml

DEFAULT_TABLE_HEIGHT = 0.75
SHAPE_SIZE_LEN = {"box": 3, "cylinder": 2, "sphere": 1, "ellipsoid": 3, "capsule": 2}


@dataclass(frozen=True)
class ObjectSpec:
    name: str
    shape: str                    # box | cylinder | sphere | ellipsoid | capsule
    size: tuple[float, ...]       # MuJoCo geom size convention for the shape
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

    @property
    def half_extents(self) -> np.ndarray:
        s = self.size
        return np.array({
            "box": (s[0], s[1], s[2]) if len(s) == 3 else (0, 0, 0),
            "cylinder": (s[0], s[0], s[-1]),
            "sphere": (s[0],) * 3,
            "ellipsoid": tuple(s[:3]) if len(s) == 3 else (0, 0, 0),
            "capsule": (s[0], s[0], s[-1] + s[0]),
        }[self.shape], dtype=float)

    @property
    def footprint_radius(self) -> float:
        """Radius of the object's xy footprint, for collision-free placement."""
        return float(np.hypot(*self.half_extents[:2]))


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


def _num_list(path, fld, value, length=None):
    if not isinstance(value, (list, tuple)) or not all(isinstance(v, (int, float)) for v in value):
        raise SpecError(path, fld, "a list of numbers", value)
    if length is not None and len(value) != length:
        raise SpecError(path, fld, f"{length} numbers", value)
    return tuple(float(v) for v in value)


def _parse_object(path, name, raw, zones) -> ObjectSpec:
    where = f"objects.{name}"
    if not isinstance(raw, dict):
        raise SpecError(path, where, "a mapping", raw)
    shape = raw.get("shape")
    if shape not in SHAPE_SIZE_LEN:
        raise SpecError(path, f"{where}.shape", f"one of {sorted(SHAPE_SIZE_LEN)}", shape)
    size = _num_list(path, f"{where}.size", raw.get("size"), SHAPE_SIZE_LEN[shape])
    pose = raw.get("pose")
    zone = raw.get("zone")
    if (pose is None) == (zone is None):
        raise SpecError(path, where, "exactly one of 'pose' or 'zone'")
    if zone is not None and zone not in zones:
        raise SpecError(path, f"{where}.zone", f"a zone from {sorted(zones)}", zone)
    xy = _num_list(path, f"{where}.pose.xy", pose["xy"], 2) if pose else None
    container = raw.get("container") or {}
    return ObjectSpec(
        name=name,
        shape=shape,
        size=size,
        mass=float(raw.get("mass", 0.1)),
        friction=float(raw.get("friction", 1.0)),
        rgba=_num_list(path, f"{where}.rgba", raw.get("rgba", [0.7, 0.7, 0.7, 1.0]), 4),
        xy=xy,
        yaw_deg=float((pose or {}).get("yaw_deg", 0.0)),
        zone=zone,
        fixed_pose=bool(raw.get("fixed_pose", False)),
        rolling_friction=_non_negative(path, f"{where}.rolling_friction", raw.get("rolling_friction", 0.0)),
        interior_half_extents=(_num_list(path, f"{where}.container.interior_half_extents",
                                         container["interior_half_extents"], 3)
                               if container else None),
        interior_offset=(_num_list(path, f"{where}.container.interior_offset",
                                   container.get("interior_offset", [0, 0, 0]), 3)
                         if container else None),
    )


def _non_negative(path: Path, field: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value < 0:
        raise SpecError(path, field, "a non-negative number", value)
    return float(value)


def parse_task(raw: dict, path: Path) -> TaskSpec:
    for key in ("name", "instruction", "objects", "metrics"):
        if key not in raw:
            raise SpecError(path, key, "a value")
    zones = raw.get("zones") or {}
    objects = {n: _parse_object(path, n, o, zones) for n, o in raw["objects"].items()}
    table = raw.get("table") or {}
    plan = raw.get("demo_plan") or []
    for i, step in enumerate(plan):
        for key in ("hand", "pick", "place"):
            if key not in step:
                raise SpecError(path, f"demo_plan[{i}].{key}", "a value")
        if step["hand"] not in ("left", "right"):
            raise SpecError(path, f"demo_plan[{i}].hand", "'left' or 'right'", step["hand"])
        for key in ("pick", "place"):
            if step[key] not in objects:
                raise SpecError(path, f"demo_plan[{i}].{key}", f"an object from {sorted(objects)}",
                                step[key])
    return TaskSpec(
        name=raw["name"],
        display_name=raw.get("display_name", raw["name"]),
        instruction=raw["instruction"],
        success_condition=raw.get("success_condition", ""),
        paper_embodiment=raw.get("paper_embodiment", ""),
        table=TableSpec(
            height=float(table.get("height", DEFAULT_TABLE_HEIGHT)),
            size_xy=_num_list(path, "table.size_xy", table.get("size_xy", [1.2, 0.8]), 2),
            thickness=float(table.get("thickness", 0.04)),
            friction=float(table.get("friction", 0.8)),
        ),
        objects=objects,
        zones=zones,
        points=raw.get("points") or {},
        demo_plan=plan,
        metrics=raw["metrics"],
        source=Path(path),
        raw=raw,
    )


@lru_cache(maxsize=64)
def load_task(name: str) -> TaskSpec:
    path = catalog_path("tasks", name, "task")
    return parse_task(load_yaml(path), path)
