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

from sim.errors import SpecError, UnknownNameError  # noqa: F401  (SpecError: imported from here by callers)
from sim.schema import read_yaml, validate
from sim.schema.channel import ChannelFile
from sim.schema.sensor_profile import (DEFAULT_OCCUPANCY_BOUNDS_M, DEFAULT_OCCUPANCY_VOXEL_M,  # noqa: F401
                                       SensorProfileFile)
from sim.schema.settings import SettingsFile

CATALOG = Path(__file__).parent / "catalog"
SETTING_SEPARATOR = "__"


def load_yaml(path: Path) -> dict:
    """Load one YAML mapping safely; errors name the file."""
    return read_yaml(path)


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
# the occupancy defaults (the table workspace at 2 cm) live with the schema: sim.schema.sensor_profile


def sensor_profile(name: str) -> SensorProfile:
    path = catalog_path("sensor_profiles", name, "sensor profile")
    raw = load_yaml(path)
    return parse_sensor_profile(raw, path)


def parse_sensor_profile(raw: dict, path=None) -> SensorProfile:
    """A profile mapping (a file's, or one built in code), checked by its schema."""
    m = validate(SensorProfileFile, raw, path)
    cams, tactile, occupancy = m.cameras, m.tactile, m.occupancy
    return SensorProfile(
        name=m.name,
        description=m.description,
        rate_hz=m.rate_hz,
        camera_ids=tuple(cams.ids),
        width=cams.width,
        height=cams.height,
        modalities=tuple(cams.modalities if cams.modalities is not None else CAMERA_MODALITIES),
        shadows=cams.shadows,
        clip_near_m=cams.clip_near_m,
        clip_far_m=cams.clip_far_m,
        tactile_enabled=tactile.enabled,
        tactile_resolution=tactile.resolution,
        tactile_step=tactile.step,
        tactile_max_range_mm=tactile.max_range_mm,
        occupancy_bounds_m=tuple(tuple(row) for row in occupancy.bounds_m),
        occupancy_voxel_size_m=occupancy.voxel_size_m,
        raw=raw,
        antialias=cams.antialias,
        tessellation=tuple(cams.tessellation) if cams.tessellation is not None else None,
    )


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
    return read_channel(catalog_path("channels", name, "channel"))


def read_channel(path: Path) -> Channel:
    """One channel file, checked by its schema."""
    m = validate(ChannelFile, load_yaml(path), path)
    return Channel(name=m.name, paper_name=m.paper_name, anchored=m.anchored,
                   resample_invariance=m.resample_invariance, resample_equivariance=m.resample_equivariance)


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


@lru_cache(maxsize=1)
def paper_settings() -> tuple[Setting, ...]:
    return read_settings(CATALOG / "settings.yaml")


def read_settings(path: Path) -> tuple[Setting, ...]:
    """A settings file (the paper's: `sim/catalog/settings.yaml`), checked by its schema."""
    m = validate(SettingsFile, load_yaml(path), path)
    return tuple(Setting(s.task, s.embodiment, s.available) for s in m.paper_settings)


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
