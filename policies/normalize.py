"""Normalisation statistics of a training set, saved beside the checkpoint as JSON, and their use.

ACT normalises joint positions and actions by mean and standard deviation, Diffusion Policy maps them to
[-1, 1] by their range (its samples are clipped there). Images: per view and channel mean and standard
deviation of the [0, 1] pixels. TacMap images are scaled to [0, 1].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MIN_SPREAD = 1e-3          # a joint that never moved: no division by ~0
SCHEMES = {"act": "mean_std", "dp": "min_max"}


def vector_stats(values: np.ndarray) -> dict[str, list[float]]:
    values = values.astype(np.float64)
    return {"mean": values.mean(0).tolist(), "std": values.std(0).tolist(),
            "min": values.min(0).tolist(), "max": values.max(0).tolist()}


def image_stats(images: np.ndarray, max_frames: int = 2000) -> dict[str, list[float]]:
    """Per-channel mean and std of uint8 [T, H, W, 3] frames (evenly subsampled to `max_frames`)."""
    pick = np.linspace(0, len(images) - 1, min(len(images), max_frames)).astype(int)
    pixels = images[pick].reshape(-1, 3).astype(np.float64) / 255.0
    return {"mean": pixels.mean(0).tolist(), "std": pixels.std(0).tolist()}


@dataclass(frozen=True)
class Normalizer:
    scheme: str                       # "mean_std" | "min_max"
    stats: dict                       # {"state": vector stats, "action": ..., "images": {view: ...}}

    def _affine(self, key: str) -> tuple[np.ndarray, np.ndarray]:
        """(offset, scale): normalized = (x - offset) / scale."""
        s = self.stats[key]
        if self.scheme == "mean_std":
            return np.asarray(s["mean"]), np.maximum(np.asarray(s["std"]), MIN_SPREAD)
        lo, hi = np.asarray(s["min"]), np.asarray(s["max"])
        return (hi + lo) / 2.0, np.maximum((hi - lo) / 2.0, MIN_SPREAD)

    def state(self, x: np.ndarray) -> np.ndarray:
        offset, scale = self._affine("state")
        return ((x - offset) / scale).astype(np.float32)

    def action(self, x: np.ndarray) -> np.ndarray:
        offset, scale = self._affine("action")
        return ((x - offset) / scale).astype(np.float32)

    def unnormalize_action(self, x: np.ndarray) -> np.ndarray:
        offset, scale = self._affine("action")
        return x.astype(np.float64) * scale + offset

    def images(self, frames: np.ndarray, views: tuple[str, ...]) -> np.ndarray:
        """uint8 [..., V, H, W, 3] -> float32 [..., V, 3, H, W], normalized per view and channel."""
        x = frames.astype(np.float32) / 255.0
        mean = np.array([self.stats["images"][v]["mean"] for v in views], np.float32)
        std = np.maximum(np.array([self.stats["images"][v]["std"] for v in views], np.float32), MIN_SPREAD)
        x = (x - mean[:, None, None, :]) / std[:, None, None, :]
        return np.moveaxis(x, -1, -3).copy()

    @staticmethod
    def tactile(frames: np.ndarray) -> np.ndarray:
        return frames.astype(np.float32) / 255.0
