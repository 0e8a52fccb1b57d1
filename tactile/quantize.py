"""TacMap depth encoding (paper appendix "Signal Semantics and Depth Quantization").

Metric ray depth d (metres) -> z = 1e3 d (mm) -> piecewise quantizer
    q(z) = z / 0.005             for z < 0.5 mm   (5 um per level)
    q(z) = (z - 0.5) / 0.03 + 100 for z >= 0.5 mm (30 um per level)
-> uint8(clip(q, 0, 255)) (the cast truncates) -> Gaussian smoothing (sigma 1.5, kernel
max(1, floor(9 / step)) rounded up to odd, evaluated in float) -> round -> uint8.
Missed or rejected samples are zero before smoothing.
"""

from __future__ import annotations

import cv2
import numpy as np

FINE_LIMIT_MM = 0.5
FINE_MM_PER_LEVEL = 0.005
COARSE_MM_PER_LEVEL = 0.03
COARSE_OFFSET = 100.0
SMOOTHING_SIGMA = 1.5
NATIVE_KERNEL = 9


def quantize_depth(distance_m: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Piecewise quantizer of the paper, before smoothing: uint8 with zeros where mask is False."""
    distance_m = np.asarray(distance_m)
    mask = np.asarray(mask, dtype=bool)
    if distance_m.shape != mask.shape:
        raise ValueError(f"distance_m shape {distance_m.shape} != mask shape {mask.shape}")
    z = distance_m[mask].astype(np.float64) * 1e3
    q = np.where(
        z < FINE_LIMIT_MM,
        z / FINE_MM_PER_LEVEL,
        (z - FINE_LIMIT_MM) / COARSE_MM_PER_LEVEL + COARSE_OFFSET,
    )
    out = np.zeros(mask.shape, dtype=np.uint8)
    out[mask] = np.clip(q, 0.0, 255.0).astype(np.uint8)
    return out


def smoothing_kernel_size(step: int) -> int:
    """max(1, floor(9 / step)) rounded up to an odd integer: 9 at step 1, 3 at step 3, 1 at step 8."""
    if int(step) != step or step < 1:
        raise ValueError(f"step must be a positive integer, got {step!r}")
    k = max(1, NATIVE_KERNEL // int(step))
    return k if k % 2 == 1 else k + 1


def smooth_tacmap(quantized: np.ndarray, step: int) -> np.ndarray:
    """Gaussian smoothing in float32 (OpenCV's default reflect-101 border), rounded back to uint8."""
    k = smoothing_kernel_size(step)
    if k == 1:
        return np.array(quantized, dtype=np.uint8, copy=True)
    blurred = cv2.GaussianBlur(
        np.asarray(quantized, dtype=np.float32), (k, k), SMOOTHING_SIGMA, sigmaY=SMOOTHING_SIGMA
    )
    return np.clip(np.rint(blurred), 0, 255).astype(np.uint8)


def encode_tacmap(distance_m: np.ndarray, mask: np.ndarray, step: int) -> np.ndarray:
    """Metric depth (metres, H x W) and contact-validity mask -> stored 8-bit tacmap (H x W)."""
    return smooth_tacmap(quantize_depth(distance_m, mask), step)


def encoding_description(step: int) -> dict:
    """The tacmap encoding at ``step`` as JSON-able settings (stored with every tactile episode)."""
    return {
        "input": "distance_along_normal_m (metres, zero where contact_mask is false)",
        "fine_limit_mm": FINE_LIMIT_MM,
        "fine_mm_per_level": FINE_MM_PER_LEVEL,
        "coarse_mm_per_level": COARSE_MM_PER_LEVEL,
        "coarse_offset": COARSE_OFFSET,
        "saturation_mm": FINE_LIMIT_MM + (255 - COARSE_OFFSET) * COARSE_MM_PER_LEVEL,
        "cast": "uint8(clip(q, 0, 255)), truncating",
        "smoothing": {"type": "gaussian", "sigma": SMOOTHING_SIGMA, "kernel": smoothing_kernel_size(step),
                      "border": "reflect_101", "evaluated_in": "float32", "output": "rint -> uint8"},
    }
