"""Per-cell metrics (task, embodiment, policy, channel) of checked records, and a cache of them per
records file so that a rebuild scores only the files that are new or changed.

The cache holds one JSON file per (file content sha256, bootstrap settings, CACHE_VERSION): the
cells of that file, exactly as computed (JSON floats round-trip). A cell split over several files
cannot be scored file by file: those files are read together and their cells computed afresh.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from episodes.atomic import file_sha256, write_text_atomic
from evaluation.metrics import NEEDED, cell_metrics
from result_tables.load import PROVENANCE_KEYS, expand, load_records
from result_tables.schema import CELL, DERIVED_FROM

CACHE_VERSION = "1"   # bump when the cell metrics (evaluation/metrics.py) change meaning


def cell_table(df: pd.DataFrame, n_boot: int, seed: int) -> pd.DataFrame:
    """The metric suite per cell (evaluation.metrics.cell_metrics), with the metrics whose source
    columns the cell's records lack (absent or empty) set to NaN (not available), and each cell's provenance: its episode
    seed range, dwell times and the provenance columns' values."""
    present = set(df.columns)
    filled = df.assign(**{c: np.nan for c in NEEDED if c not in present})
    filled = filled.drop(columns=[c for c in ("_file", "_row") if c in filled.columns])
    cells = cell_metrics(filled, by=CELL, n_boot=n_boot, seed=seed)
    # per cell, so that the answer does not depend on which files were scored together; a cell of
    # error episodes only has nothing to read: its metrics keep cell_metrics' failure values
    keys = [df[c] for c in CELL]
    errors = df["termination"].eq("error") if "termination" in df else pd.Series(False, index=df.index)
    all_errors = errors.groupby(keys, sort=True).all().to_numpy()
    for metric, sources in DERIVED_FROM.items():
        recorded = np.ones(len(cells), dtype=bool)
        for source in sources:
            recorded &= (df[source].notna().groupby(keys, sort=True).any().to_numpy() if source in present
                         else False)
        cells.loc[~recorded & ~all_errors, metric] = np.nan
    extras = []
    for key, g in df.groupby(list(CELL), sort=True):
        seeds = pd.to_numeric(g["seed"], errors="coerce").dropna() if "seed" in g else pd.Series(dtype=float)
        row = dict(zip(CELL, key))
        row["seed_min"] = int(seeds.min()) if len(seeds) else None
        row["seed_max"] = int(seeds.max()) if len(seeds) else None
        row["dwell_s"] = _joined(g["dwell_s"]) if "dwell_s" in g else None
        for name in PROVENANCE_KEYS:
            row[name] = _joined(g[name]) if name in g else None
        extras.append(row)
    return cells.merge(pd.DataFrame(extras, columns=[*CELL, "seed_min", "seed_max", "dwell_s", *PROVENANCE_KEYS]),
                       on=list(CELL), how="left")


def _joined(series: pd.Series) -> str | None:
    values = sorted({str(v) for v in series.dropna()})
    return "; ".join(values) if values else None


@dataclass
class CellResult:
    cells: pd.DataFrame
    files: list[dict]          # {"file", "sha256"} per records file, in order
    reused: int = 0            # files whose cells came from the cache
    computed: int = 0          # files scored now


def collect_cells(paths, n_boot: int, seed: int, cache_dir: str | Path | None = None) -> CellResult:
    """Cells of every records file (folders: every parquet/CSV file below). With ``cache_dir``, a file
    whose content was scored before with the same settings is not read again."""
    files = expand(paths)
    if not files:
        load_records(paths)   # raises RecordsError: no records files found
    if cache_dir is None:
        loaded = load_records(files)
        frame = pd.concat([f.frame for f in loaded], ignore_index=True)
        return CellResult(cell_table(frame, n_boot, seed), [{"file": str(f.path), "sha256": f.sha256} for f in loaded],
                          computed=len(loaded))
    cache = Path(cache_dir)
    hashes = {p: file_sha256(p) if p.is_file() else None for p in files}
    entry = lambda sha: cache / f"{sha}-b{n_boot}-s{seed}-v{CACHE_VERSION}.json"  # noqa: E731
    per_file, misses = {}, []
    for p in files:
        if hashes[p] and entry(hashes[p]).is_file():
            per_file[p] = _read_entry(entry(hashes[p]))
        else:
            misses.append(p)
    loaded = load_records(misses) if misses else []   # refuses bad files, naming each
    if loaded:   # scored in one batch (per-call overhead), then split by file for the cache
        frame = pd.concat([f.frame for f in loaded], ignore_index=True)
        batch = cell_table(frame, n_boot, seed)
        owners = frame.groupby(list(CELL), sort=False)["_file"].nunique().to_dict()
        row_of = {k: i for i, k in enumerate(zip(*(batch[c] for c in CELL)))}
        for f in loaded:
            keys = sorted(set(zip(*(f.frame[c] for c in CELL))), key=row_of.get)
            per_file[f.path] = batch.iloc[[row_of[k] for k in keys]].reset_index(drop=True)
            if all(owners[k] == 1 for k in keys):   # a cell shared with another file is not the file's alone
                _write_entry(entry(f.sha256), per_file[f.path])
    shared = _shared_cells(per_file)
    if shared:   # a cell spread over several files: score those files' rows together
        together = load_records(shared)
        frame = pd.concat([f.frame for f in together], ignore_index=True)
        for p in shared:
            per_file.pop(p)
        per_file["shared"] = cell_table(frame, n_boot, seed)
    cells = pd.concat(list(per_file.values()), ignore_index=True).sort_values(list(CELL), kind="stable")
    return CellResult(cells.reset_index(drop=True), [{"file": str(p), "sha256": hashes[p]} for p in files],
                      reused=len(files) - len(misses), computed=len(misses))


def _shared_cells(per_file: dict) -> list[Path]:
    owners: dict[tuple, list] = {}
    for p, cells in per_file.items():
        for key in cells[list(CELL)].itertuples(index=False, name=None):
            owners.setdefault(key, []).append(p)
    return sorted({p for ps in owners.values() if len(ps) > 1 for p in ps})


def _write_entry(path: Path, cells: pd.DataFrame) -> None:
    body = {"columns": list(cells.columns), "rows": [[_plain(v) for v in row] for row in cells.to_numpy(dtype=object)]}
    write_text_atomic(path, json.dumps(body))


def _read_entry(path: Path) -> pd.DataFrame:
    body = json.loads(path.read_text(encoding="utf-8"))
    return pd.DataFrame(body["rows"], columns=body["columns"])


def _plain(v):
    if isinstance(v, np.generic):
        v = v.item()
    if v is None or (isinstance(v, float) and np.isnan(v)):
        return float("nan") if isinstance(v, float) else None
    return v
