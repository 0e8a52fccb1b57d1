"""Tacmap heatmap panels: one colour-mapped tile per site in a labelled grid (RGB uint8)."""

from __future__ import annotations

import math

import cv2
import numpy as np

TILE_MIN_PX = 160
LABEL_PX = 22
TITLE_PX = 30
GAP_PX = 6
FONT = cv2.FONT_HERSHEY_SIMPLEX
BACKGROUND = 255
COLORMAP = cv2.COLORMAP_INFERNO  # 0 (no contact) is black; deeper contact is brighter


def _tile(tacmap: np.ndarray, scale: int) -> np.ndarray:
    if tacmap.ndim != 2 or tacmap.dtype != np.uint8:
        raise ValueError(f"a tacmap must be a uint8 (H, W) array, got {tacmap.dtype} {tacmap.shape}")
    big = cv2.resize(tacmap, None, fx=scale, fy=scale, interpolation=cv2.INTER_NEAREST)
    return cv2.cvtColor(cv2.applyColorMap(big, COLORMAP), cv2.COLOR_BGR2RGB)


def _text(image: np.ndarray, text: str, x: int, y: int, height: int, max_width: int) -> None:
    """Dark text fitted into a box of ``height`` x ``max_width`` whose top-left is (x, y)."""
    scale = 0.5 if height < TITLE_PX else 0.7
    (width, _), _ = cv2.getTextSize(text, FONT, scale, 1)
    if width > max_width:
        scale *= max_width / width
    cv2.putText(image, text, (x + 2, y + height - 7), FONT, scale, (20, 20, 20), 1, cv2.LINE_AA)


def tacmap_panel(tacmaps: dict[str, np.ndarray], title: str | None = None, columns: int | None = None) -> np.ndarray:
    """Grid of labelled site heatmaps (insertion order, ``columns`` per row; default up to 5)."""
    if not tacmaps:
        raise ValueError("tacmap_panel needs at least one tacmap")
    shapes = {np.asarray(t).shape for t in tacmaps.values()}
    if len(shapes) != 1:
        raise ValueError(f"all tacmaps must share one shape, got {sorted(shapes)}")
    h, w = shapes.pop()[:2]
    scale = max(1, math.ceil(TILE_MIN_PX / max(h, w)))
    columns = columns or min(5, len(tacmaps))
    rows = math.ceil(len(tacmaps) / columns)
    cell_w, cell_h = w * scale + GAP_PX, h * scale + LABEL_PX + GAP_PX
    top = TITLE_PX if title else 0
    panel = np.full((top + rows * cell_h + GAP_PX, columns * cell_w + GAP_PX, 3), BACKGROUND, np.uint8)
    if title:
        _text(panel, title, GAP_PX, 0, TITLE_PX, panel.shape[1] - 2 * GAP_PX)
    for i, (name, tacmap) in enumerate(tacmaps.items()):
        x = GAP_PX + (i % columns) * cell_w
        y = top + GAP_PX + (i // columns) * cell_h
        _text(panel, name, x, y, LABEL_PX, w * scale)
        panel[y + LABEL_PX : y + LABEL_PX + h * scale, x : x + w * scale] = _tile(np.asarray(tacmap), scale)
    return panel
