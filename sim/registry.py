"""Registries over the YAML catalogs in `sim/catalog/`.

A new task, hand, sensor profile or channel is a new file; nothing here branches on names.
Every lookup validates the name and fails fast with the list of valid names.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import yaml

from sim.errors import SpecError, UnknownNameError

CATALOG = Path(__file__).parent / "catalog"
SETTING_SEPARATOR = "__"


def load_yaml(path: Path) -> dict:
    """Load one YAML mapping safely; errors name the file."""
    try:
        with open(path, encoding="utf-8") as f:
            data = yaml.safe_load(f)
    except yaml.YAMLError as exc:
        raise SpecError(path, "<document>", f"valid YAML ({exc})") from exc
    if not isinstance(data, dict):
        raise SpecError(path, "<document>", "a YAML mapping at the top level", type(data).__name__)
    return data


def _files(kind: str) -> dict[str, Path]:
    return {p.stem: p for p in sorted((CATALOG / kind).glob("*.yaml"))}


def names(kind: str) -> list[str]:
    """Names of the entries of one catalog folder (arms, hands, embodiments, tasks, ...)."""
    return sorted(_files(kind))


def catalog_path(kind: str, name: str, label: str | None = None) -> Path:
    files = _files(kind)
    if name not in files:
        raise UnknownNameError(label or kind.rstrip("s"), name, files)
    return files[name]


# ---------------------------------------------------------------- sensor profiles


@dataclass(frozen=True)
class SensorProfile:
    """What is rendered, at which resolution and rate."""

    name: str
    description: str
    rate_hz: int
    camera_ids: tuple[str, ...]
    width: int
    height: int
    modalities: tuple[str, ...]
    shadows: bool
    clip_near_m: float
    clip_far_m: float
    tactile_enabled: bool
    tactile_resolution: int
    tactile_step: int
    tactile_max_range_mm: float
    occupancy_bounds_m: tuple[tuple[float, float, float], tuple[float, float, float]]   # world [lo, hi]
    occupancy_voxel_size_m: float
    raw: dict
    # multisample anti-aliasing of the RGB pass (4 samples): ~2.8x the RGB render time on a CPU renderer
    antialias: bool = False
    # (slices, stacks) of MuJoCo's tessellated primitives; None: the model's own (28, 16). The triangles are
    # most of a small image's render cost: (8, 4) draws four 64x48 views in about a third of the time
    tessellation: tuple[int, int] | None = None

    @property
    def content_hash(self) -> str:
        """Stable hash of everything that changes the rendered bytes; keys output folders and
        Dagster code versions so that a changed profile marks renders stale."""
        # the parsed render switches too: a profile that leaves a switch out gets its default, and
        # a default that changes (anti-aliasing went from MuJoCo's on to off) must change the hash
        blob = json.dumps({"profile": self.raw, "shadows": self.shadows, "antialias": self.antialias},
                          sort_keys=True).encode()
        return hashlib.sha256(blob).hexdigest()[:12]

    @property
    def tactile_shape(self) -> tuple[int, int]:
        n = len(range(0, self.tactile_resolution, self.tactile_step))
        return (n, n)


CAMERA_MODALITIES = ("rgb", "depth")
# labels derived from the same render pass (sim/labels); segmentation is a b2d addition to the paper's list
LABEL_MODALITIES = ("segmentation", "box2d", "box3d", "occupancy")
# the table workspace: 1.2 x 0.8 m tables, tops at 0.70 - 0.80 m, objects up to ~0.45 m tall
DEFAULT_OCCUPANCY_BOUNDS_M = ((-0.6, -0.4, 0.65), (0.6, 0.4, 1.25))
DEFAULT_OCCUPANCY_VOXEL_M = 0.02


def sensor_profile(name: str) -> SensorProfile:
    path = catalog_path("sensor_profiles", name, "sensor profile")
    raw = load_yaml(path)
    return parse_sensor_profile(raw, path)


def parse_sensor_profile(raw: dict, path=None) -> SensorProfile:
    def need(mapping, key, kind, field):
        if key not in mapping:
            raise SpecError(path, field, f"a {kind}")
        value = mapping[key]
        if kind == "positive integer" and (not isinstance(value, int) or value <= 0):
            raise SpecError(path, field, "a positive integer", value)
        return value

    def flag(mapping, key, field):
        value = mapping.get(key, False)
        if not isinstance(value, bool):
            raise SpecError(path, field, "true or false", value)
        return value

    cams = need(raw, "cameras", "mapping", "cameras")
    tactile = raw.get("tactile", {"enabled": False})
    modalities = tuple(cams.get("modalities", CAMERA_MODALITIES))
    for m in modalities:
        if m not in CAMERA_MODALITIES + LABEL_MODALITIES:
            raise SpecError(path, "cameras.modalities", f"entries from {list(CAMERA_MODALITIES + LABEL_MODALITIES)}", m)
    bounds, voxel = _occupancy(raw.get("occupancy", {}), path)
    return SensorProfile(
        name=need(raw, "name", "string", "name"),
        description=raw.get("description", ""),
        rate_hz=need(raw, "rate_hz", "positive integer", "rate_hz"),
        camera_ids=tuple(need(cams, "ids", "list of camera ids", "cameras.ids")),
        width=need(cams, "width", "positive integer", "cameras.width"),
        height=need(cams, "height", "positive integer", "cameras.height"),
        modalities=modalities,
        shadows=flag(cams, "shadows", "cameras.shadows"),
        clip_near_m=float(cams.get("clip_near_m", 0.01)),
        clip_far_m=float(cams.get("clip_far_m", 5.0)),
        tactile_enabled=bool(tactile.get("enabled", False)),
        tactile_resolution=int(tactile.get("resolution", 240)),
        tactile_step=int(tactile.get("step", 1)),
        tactile_max_range_mm=float(tactile.get("max_range_mm", 15.0)),
        occupancy_bounds_m=bounds,
        occupancy_voxel_size_m=voxel,
        raw=raw,
        antialias=flag(cams, "antialias", "cameras.antialias"),
        tessellation=_tessellation(cams.get("tessellation"), path),
    )


def _tessellation(value, path) -> tuple[int, int] | None:
    if value is None:
        return None
    if not (isinstance(value, (list, tuple)) and len(value) == 2
            and all(isinstance(v, int) and not isinstance(v, bool) and 3 <= v <= 128 for v in value)):
        raise SpecError(path, "cameras.tessellation", "[slices, stacks], integers from 3 to 128", value)
    return (value[0], value[1])


def _occupancy(block, path) -> tuple[tuple, float]:
    """The `occupancy` block: world bounds [[x0, y0, z0], [x1, y1, z1]] and voxel edge (m)."""
    from sim.labels.grid import grid_shape

    if not isinstance(block, dict) or set(block) - {"bounds_m", "voxel_size_m"}:
        raise SpecError(path, "occupancy", "a mapping with keys [bounds_m, voxel_size_m]", block)
    bounds = block.get("bounds_m", DEFAULT_OCCUPANCY_BOUNDS_M)
    voxel = block.get("voxel_size_m", DEFAULT_OCCUPANCY_VOXEL_M)
    numbers = isinstance(bounds, (list, tuple)) and len(bounds) == 2 and all(
        isinstance(row, (list, tuple)) and len(row) == 3
        and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in row) for row in bounds)
    if not numbers:
        raise SpecError(path, "occupancy.bounds_m", "[[x0, y0, z0], [x1, y1, z1]] in metres", bounds)
    if isinstance(voxel, bool) or not isinstance(voxel, (int, float)):
        raise SpecError(path, "occupancy.voxel_size_m", "a positive length in metres", voxel)
    try:
        grid_shape(bounds, float(voxel))
    except ValueError as exc:
        raise SpecError(path, "occupancy", str(exc)) from exc
    return tuple(tuple(float(v) for v in row) for row in bounds), float(voxel)


# ---------------------------------------------------------------- channels


@dataclass(frozen=True)
class Channel:
    """A generalization channel: which factor groups are resampled, and whether an anchor is used."""

    name: str
    paper_name: str
    anchored: bool
    resample_invariance: bool
    resample_equivariance: bool


def channel(name: str) -> Channel:
    path = catalog_path("channels", name, "channel")
    raw = load_yaml(path)
    try:
        return Channel(
            name=raw["name"],
            paper_name=raw["paper_name"],
            anchored=bool(raw["anchored"]),
            resample_invariance=bool(raw["resample_invariance"]),
            resample_equivariance=bool(raw["resample_equivariance"]),
        )
    except KeyError as exc:
        raise SpecError(path, exc.args[0], "a value") from exc


CHANNEL_ORDER = ("none", "equi_only", "inv_only", "inv_equi")


def channel_names() -> list[str]:
    found = names("channels")
    return [c for c in CHANNEL_ORDER if c in found] + [c for c in found if c not in CHANNEL_ORDER]


# ---------------------------------------------------------------- settings


@dataclass(frozen=True)
class Setting:
    task: str
    embodiment: str
    marked_available: bool = True    # settings.yaml's flag: the task builds on this embodiment

    @property
    def key(self) -> str:
        return f"{self.task}{SETTING_SEPARATOR}{self.embodiment}"

    @property
    def available(self) -> bool:
        """Marked available and both the task and the embodiment files are in the catalog."""
        return self.marked_available and self.task in names("tasks") and self.embodiment in names("embodiments")

    @property
    def recordable(self) -> bool:
        """Available and its task has a demonstration plan for the scripted operator."""
        if not self.available:
            return False
        from sim.tasks import load_task     # tasks import the registry: load lazily
        return bool(load_task(self.task).demo_plan)


@lru_cache(maxsize=1)
def paper_settings() -> tuple[Setting, ...]:
    path = CATALOG / "settings.yaml"
    out = []
    for i, s in enumerate(load_yaml(path)["paper_settings"]):
        flag = s.get("available", True)
        if not isinstance(flag, bool):
            raise SpecError(path, f"paper_settings[{i}].available", "true or false", flag)
        out.append(Setting(s["task"], s["embodiment"], flag))
    return tuple(out)


def parse_setting_key(key: str) -> Setting:
    """`<task>__<embodiment>` -> Setting; both names validated."""
    if SETTING_SEPARATOR not in key:
        raise UnknownNameError("setting", key, [s.key for s in paper_settings()])
    task, embodiment = key.split(SETTING_SEPARATOR, 1)
    validate_name("task", task)
    validate_name("embodiment", embodiment)
    listed = {s.key: s for s in paper_settings()}
    return listed.get(key, Setting(task, embodiment))


def validate_name(kind: str, name: str) -> str:
    """Fail fast on an unknown task / embodiment / channel / profile name."""
    folder = {"task": "tasks", "embodiment": "embodiments", "channel": "channels",
              "sensor profile": "sensor_profiles", "profile": "sensor_profiles"}[kind]
    if name not in names(folder):
        raise UnknownNameError(kind, name, names(folder))
    return name
