"""Procedural visual-asset catalogs for the invariance factors.

The paper draws backgrounds from 60 iTHOR scenes (50 seen / 10 unseen), tabletop textures from
11,824 materials (9,436 / 2,388) and distractors from 68 objects (52 / 16). Those assets are
behind downloads, so b2d generates catalogs of the same sizes and splits procedurally: every id
maps deterministically to parameters (MuJoCo builtin textures, colours from a category palette,
primitive shapes). Splits are a stable hash ordering, so they never change between runs.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

N_BACKGROUNDS, N_BACKGROUNDS_UNSEEN = 60, 10
N_TEXTURES, N_TEXTURES_UNSEEN = 11_824, 2_388
N_DISTRACTORS, N_DISTRACTORS_UNSEEN = 68, 16

TEXTURE_CATEGORIES = ("carpet", "fabric", "flooring", "leather", "metal", "rust", "stone", "wood")
# Base colour per category (rgb); samples vary around it.
_CATEGORY_RGB = {
    "carpet": (0.45, 0.30, 0.30), "fabric": (0.35, 0.40, 0.55), "flooring": (0.60, 0.50, 0.38),
    "leather": (0.40, 0.25, 0.15), "metal": (0.62, 0.63, 0.66), "rust": (0.55, 0.28, 0.12),
    "stone": (0.50, 0.50, 0.47), "wood": (0.55, 0.38, 0.22),
}
_BUILTINS = ("checker", "gradient", "flat")
DISTRACTOR_SHAPES = ("box", "cylinder", "sphere", "capsule")


def _stable_unit(text: str) -> float:
    return int.from_bytes(hashlib.sha256(text.encode()).digest()[:8], "big") / 2**64


def _rng_for(text: str) -> np.random.Generator:
    return np.random.default_rng(int.from_bytes(hashlib.sha256(text.encode()).digest()[:8], "big"))


def _split(prefix: str, count: int, n_unseen: int) -> tuple[tuple[str, ...], tuple[str, ...]]:
    ids = [f"{prefix}_{i:05d}" for i in range(count)]
    ordered = sorted(ids, key=_stable_unit)
    unseen = set(ordered[:n_unseen])
    return tuple(i for i in ids if i not in unseen), tuple(i for i in ids if i in unseen)


@dataclass(frozen=True)
class AssetCatalog:
    kind: str
    seen: tuple[str, ...]
    unseen: tuple[str, ...]

    def ids(self, split: str) -> tuple[str, ...]:
        return {"seen": self.seen, "unseen": self.unseen}[split]


BACKGROUNDS = AssetCatalog("background", *_split("bg", N_BACKGROUNDS, N_BACKGROUNDS_UNSEEN))
TEXTURES = AssetCatalog("texture", *_split("tex", N_TEXTURES, N_TEXTURES_UNSEEN))
DISTRACTORS = AssetCatalog("distractor", *_split("dis", N_DISTRACTORS, N_DISTRACTORS_UNSEEN))


def background_params(asset_id: str) -> dict:
    """A room stand-in: sky gradient colours for the skybox and a floor colour."""
    rng = _rng_for(asset_id)
    top = rng.uniform(0.3, 0.95, 3)
    bottom = top * rng.uniform(0.3, 0.7)
    floor = rng.uniform(0.2, 0.7, 3)
    return {"id": asset_id, "sky_rgb1": top.round(4).tolist(), "sky_rgb2": bottom.round(4).tolist(),
            "floor_rgb": floor.round(4).tolist()}


def texture_params(asset_id: str) -> dict:
    rng = _rng_for(asset_id)
    category = TEXTURE_CATEGORIES[int(rng.integers(len(TEXTURE_CATEGORIES)))]
    base = np.array(_CATEGORY_RGB[category])
    rgb1 = np.clip(base + rng.normal(0, 0.08, 3), 0, 1)
    rgb2 = np.clip(rgb1 * rng.uniform(0.6, 0.95), 0, 1)
    return {"id": asset_id, "category": category, "builtin": _BUILTINS[int(rng.integers(3))],
            "rgb1": rgb1.round(4).tolist(), "rgb2": rgb2.round(4).tolist(),
            "repeat": int(rng.integers(2, 9))}


def distractor_params(asset_id: str) -> dict:
    rng = _rng_for(asset_id)
    shape = DISTRACTOR_SHAPES[int(rng.integers(len(DISTRACTOR_SHAPES)))]
    size = {"box": rng.uniform(0.02, 0.05, 3), "cylinder": rng.uniform([0.02, 0.02], [0.04, 0.06]),
            "sphere": rng.uniform(0.02, 0.04, 1), "capsule": rng.uniform([0.015, 0.02], [0.03, 0.04])}[shape]
    return {"id": asset_id, "shape": shape, "size": size.round(4).tolist(),
            "rgba": [*rng.uniform(0.1, 0.9, 3).round(4).tolist(), 1.0],
            "mass": round(float(rng.uniform(0.05, 0.3)), 4)}


NOMINAL_BACKGROUND = {"id": "nominal", "sky_rgb1": [0.62, 0.70, 0.80], "sky_rgb2": [0.25, 0.28, 0.32],
                      "floor_rgb": [0.42, 0.40, 0.38]}
NOMINAL_TEXTURE = {"id": "nominal", "category": "wood", "builtin": "flat", "rgb1": [0.56, 0.42, 0.28],
                   "rgb2": [0.50, 0.37, 0.24], "repeat": 1}
NOMINAL_LIGHTING = {
    "distant": {"intensity": 1250.0, "color": [1.0, 1.0, 1.0], "pitch_deg": -55.0, "yaw_deg": 0.0,
                "angular_size_deg": 0.75},
    "dome": {"intensity": 250.0, "color": [0.9, 0.9, 0.8], "exposure": 0.0},
}
