"""Feature statistics in lerobot's form: min, max, mean, std, count and the quantiles q01, q10, q50, q90,
q99 per feature (lerobot 0.4+ writes those, and GR00T only accepts a meta/stats.json that has q01/q99).

Vectors reduce over frames (shape [D]); images reduce over frames and pixels per channel, are scaled to
[0, 1] and keep the shape [C, 1, 1]; count is the number of frames, as a one-element list. Images are
accumulated frame chunk by frame chunk (every frame; quantiles from an exact 256-bin histogram), so
memory stays bounded; like lerobot, images whose longer side reaches 300 pixels are strided down to
about 150 first (a 640x480 view counts every 4th pixel of every 4th row). Episode quantiles are exact;
dataset statistics combine episodes as lerobot's `aggregate_stats` does: count-weighted mean, pooled
variance, and for quantiles the envelope (the lowest episode value for q <= 50, the highest above), a
bound rather than an estimate (lerobot 0.6's rule; 0.4 averaged episode quantiles by count)."""

from __future__ import annotations

import numpy as np

QUANTILES = (0.01, 0.10, 0.50, 0.90, 0.99)
QUANTILE_KEYS = tuple(f"q{round(q * 100):02d}" for q in QUANTILES)


def vector_stats(values: np.ndarray) -> dict[str, np.ndarray]:
    """Stats of a [T] or [T, D] array (booleans count as 0/1)."""
    a = np.asarray(values, dtype=np.float64)
    keep = a.ndim == 1      # lerobot keeps a scalar feature's stats as a one-element array
    out = {"min": np.min(a, axis=0, keepdims=keep), "max": np.max(a, axis=0, keepdims=keep),
           "mean": np.mean(a, axis=0, keepdims=keep), "std": np.std(a, axis=0, keepdims=keep),
           "count": np.array([len(a)])}
    for key, value in zip(QUANTILE_KEYS, np.quantile(a, QUANTILES, axis=0, keepdims=keep)):
        out[key] = value
    return out


def stride(height: int, width: int, target: int = 150, threshold: int = 300) -> int:
    """lerobot's `auto_downsample_height_width` step: 1 below the threshold, else longer side // target."""
    return 1 if max(height, width) < threshold else max(height, width) // target


class ImageStats:
    """Per-channel stats of uint8 frames [N, H, W, C] (or [N, H, W] for one channel), all from one exact
    256-bin histogram per channel: no float copy of the frames is ever made."""

    LEVELS = np.arange(256, dtype=np.float64)

    def __init__(self):
        self.n = 0
        self.histogram = None

    def add(self, frames: np.ndarray) -> None:
        a = np.asarray(frames)
        if a.dtype != np.uint8:
            raise TypeError(f"image stats need uint8 frames, got {a.dtype}")
        if a.ndim == 3:
            a = a[..., None]
        a = a[:, ::stride(a.shape[1], a.shape[2]), ::stride(a.shape[1], a.shape[2])]
        counts = np.stack([np.bincount(a[..., c].reshape(-1), minlength=256) for c in range(a.shape[-1])])
        self.histogram = counts if self.histogram is None else self.histogram + counts
        self.n += a.shape[0]

    def result(self) -> dict[str, np.ndarray]:
        h = self.histogram.astype(np.float64)
        pixels = h.sum(axis=1)
        mean = h @ self.LEVELS / pixels
        var = np.maximum(h @ self.LEVELS ** 2 / pixels - mean ** 2, 0.0)
        present = self.histogram > 0

        def shaped(v):
            return (np.asarray(v, dtype=np.float64) / 255.0).reshape(-1, 1, 1)

        out = {"min": shaped(present.argmax(axis=1)), "max": shaped(255 - present[:, ::-1].argmax(axis=1)),
               "mean": shaped(mean), "std": shaped(np.sqrt(var)), "count": np.array([self.n])}
        cumulative = np.cumsum(self.histogram, axis=1)
        for key, q in zip(QUANTILE_KEYS, QUANTILES):
            # the smallest level whose cumulative share reaches q (numpy's "inverted_cdf")
            out[key] = shaped([np.searchsorted(row, q * row[-1]) for row in cumulative])
        return out


def aggregate(per_episode: list[dict[str, dict[str, np.ndarray]]]) -> dict[str, dict[str, np.ndarray]]:
    """Dataset stats from episode stats (count-weighted mean, pooled variance)."""
    out = {}
    for key in per_episode[0]:
        items = [s[key] for s in per_episode]
        counts = np.array([int(s["count"][0]) for s in items], dtype=np.float64)
        means = np.stack([s["mean"] for s in items])
        variances = np.stack([s["std"] ** 2 for s in items])
        weights = counts.reshape((-1,) + (1,) * (means.ndim - 1))
        mean = (means * weights).sum(axis=0) / counts.sum()
        var = ((variances + (means - mean) ** 2) * weights).sum(axis=0) / counts.sum()
        out[key] = {"min": np.min(np.stack([s["min"] for s in items]), axis=0),
                    "max": np.max(np.stack([s["max"] for s in items]), axis=0),
                    "mean": mean, "std": np.sqrt(var), "count": np.array([int(counts.sum())])}
        for q in QUANTILE_KEYS:
            stacked = np.stack([s[q] for s in items])
            out[key][q] = stacked.min(axis=0) if int(q[1:]) <= 50 else stacked.max(axis=0)
    return out


def to_json(stats: dict[str, dict[str, np.ndarray]]) -> dict:
    return {key: {name: np.asarray(v).tolist() for name, v in s.items()} for key, s in stats.items()}
