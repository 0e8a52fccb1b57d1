"""Records files -> the output folder: summary.json, tables.md, tables.tex, index.html and the PNG
figures. The folder is assembled beside the target and moved into place whole; an existing target is
replaced only when it is an earlier output of this builder."""

from __future__ import annotations

import json
import math
from pathlib import Path

from episodes.atomic import atomic_dir
from evaluation.metrics import LEVEL, N_BOOT, SEED
from result_tables.aggregate import aggregate
from result_tables.cells import CellResult, collect_cells
from result_tables.html import page
from result_tables.provenance import provenance
from result_tables.text import latex, markdown

KIND = "b2d result tables"
FIGURE_NAMES = ("sr_per_channel.png", "rr_heatmap.png", "sr_vs_lscr.png")   # result_tables.plots.FIGURES
OUTPUTS = ("summary.json", "tables.md", "tables.tex", "index.html", *FIGURE_NAMES)


def summarize(paths, n_boot: int = N_BOOT, seed: int = SEED, given: dict | None = None,
              cache_dir: str | Path | None = None, level: float = LEVEL) -> tuple[dict, CellResult]:
    """The summary (every number, JSON-ready) and the cells it came from (with cache statistics)."""
    result = collect_cells(paths, n_boot, seed, cache_dir)
    summary = {"kind": KIND, "version": 1,
               "metadata": provenance(result.cells, result.files, n_boot, seed, given, level),
               **aggregate(result.cells, n_boot, seed, level)}
    summary["metadata"]["missing_cells"] = len(summary["missing_cells"])
    return summary, result


def _is_previous(folder: Path) -> bool:
    try:
        return json.loads((folder / "summary.json").read_text(encoding="utf-8")).get("kind") == KIND
    except (OSError, ValueError, AttributeError):
        return False


def _clean(value):
    """NaN -> None everywhere (strict JSON)."""
    if isinstance(value, float) and math.isnan(value):
        return None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_clean(v) for v in value]
    return value


def write_outputs(summary: dict, out: str | Path) -> Path:
    from result_tables.plots import FIGURES   # matplotlib only when figures are drawn

    figures = {name: draw(summary) for name, draw in FIGURES.items()}
    texts = {"summary.json": json.dumps(_clean(summary), indent=1, sort_keys=True, allow_nan=False) + "\n",
             "tables.md": markdown(summary), "tables.tex": latex(summary), "index.html": page(summary, figures)}
    with atomic_dir(out, _is_previous) as tmp:
        for name, text in texts.items():
            (tmp / name).write_text(text, encoding="utf-8")
        for name, png in figures.items():
            (tmp / name).write_bytes(png)
    return Path(out)


def build_tables(paths, out: str | Path, n_boot: int = N_BOOT, seed: int = SEED, given: dict | None = None,
                 cache_dir: str | Path | None = None) -> tuple[dict, CellResult]:
    if Path(out).exists() and not _is_previous(Path(out)):   # refuse before the work, not after
        raise FileExistsError(out)
    summary, result = summarize(paths, n_boot, seed, given, cache_dir)
    write_outputs(summary, out)
    return summary, result
