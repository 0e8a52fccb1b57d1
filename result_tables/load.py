"""Read records files (parquet or CSV) and check them against the contract (schema.py).

Every file is checked in full before anything is refused, so one message lists every problem: the
file, the column and the rows (0-based data rows of that file).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from episodes.atomic import file_sha256
from evaluation.metrics import CHANNELS
from result_tables.schema import ALIASES, EPISODE_KEY, KINDS, LABELS, REQUIRED, RecordsError

SUFFIXES = (".parquet", ".csv")
PROVENANCE_KEYS = ("code_version", "sensor_profile_hash", "horizon_rule")   # parquet key-value metadata
_TRUE, _FALSE = {"true", "1", "yes", "t", "y", "1.0"}, {"false", "0", "no", "f", "n", "0.0"}


@dataclass
class RecordsFile:
    path: Path
    sha256: str
    frame: pd.DataFrame       # checked and normalised; columns _file and _row added
    provenance: dict          # PROVENANCE_KEYS found in the file's own metadata


def expand(paths) -> list[Path]:
    """Files as given; a folder stands for every parquet/CSV file below it (sorted)."""
    out = []
    for p in map(Path, paths):
        if p.is_dir():
            out.extend(sorted(f for f in p.rglob("*") if f.suffix in SUFFIXES and not f.name.startswith(".")))
        else:
            out.append(p)
    return out


def _read(path: Path) -> tuple[pd.DataFrame, dict]:
    if path.suffix == ".parquet":
        meta = pq.read_schema(path).metadata or {}
        found = {k: meta[k.encode()].decode() for k in PROVENANCE_KEYS if k.encode() in meta}
        return pd.read_parquet(path), found
    # only an empty field is missing: "None" is a channel name (the paper's label), not a null
    return pd.read_csv(path, keep_default_na=False, na_values=[""]), {}


def _flag(value):
    """True / False / None (missing) from a bool, 0/1 or a true/false word; raises on anything else."""
    if value is None or (isinstance(value, float) and np.isnan(value)) or value is pd.NA:
        return None
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    text = str(value).strip().lower()
    if text in _TRUE:
        return True
    if text in _FALSE:
        return False
    if text in ("", "nan", "none", "null"):
        return None
    raise ValueError(value)


def check(df: pd.DataFrame, where: str) -> tuple[pd.DataFrame, list]:
    """The normalised frame and the problems found [(file, column, what, rows)]."""
    problems = []
    missing = [c.name for c in REQUIRED if c.name not in df.columns]
    if missing:
        for name in missing:
            problems.append((where, name, f"missing; the records contract requires {[c.name for c in REQUIRED]}", []))
        return df, problems
    if df.empty:
        return df, [(where, "-", "no episode rows", [])]
    df = df.reset_index(drop=True).copy()
    for c in REQUIRED:
        if c.kind in ("text", "any"):
            empty = df[c.name].isna() | df[c.name].astype(str).str.strip().eq("")
            if empty.any():
                problems.append((where, c.name, "empty values", list(df.index[empty])))
    channel = df["channel"].astype(str).str.strip().str.lower().map(ALIASES)
    unknown = channel.isna() & df["channel"].notna()
    if unknown.any():
        names = sorted(set(df.loc[unknown, "channel"].astype(str)))
        problems.append((where, "channel", f"unknown channel {names}; valid: {list(CHANNELS)} "
                                           f"(or the paper's {list(LABELS.values())})", list(df.index[unknown])))
    df["channel"] = channel.where(~unknown, df["channel"])
    for name, kind in KINDS.items():
        if name not in df.columns:
            continue
        if kind == "flag":
            parsed, bad = [], []
            for i, v in df[name].items():
                try:
                    parsed.append(_flag(v))
                except ValueError:
                    parsed.append(None)
                    bad.append(i)
            if bad:
                problems.append((where, name, "expected true/false or 1/0", bad))
            df[name] = pd.Series(parsed, index=df.index, dtype=object)
        elif kind in ("number", "fraction"):
            values = pd.to_numeric(df[name], errors="coerce")
            bad = values.isna() & df[name].notna() & ~df[name].astype(str).str.strip().str.lower().isin(
                ["", "nan", "none", "null"])
            if bad.any():
                problems.append((where, name, "expected a number", list(df.index[bad])))
            if kind == "fraction":
                out = values.notna() & ((values < 0) | (values > 1))
                if out.any():
                    problems.append((where, name, "expected a fraction in [0, 1]", list(df.index[out])))
            df[name] = values
    errors = df["termination"].eq("error") if "termination" in df else pd.Series(False, index=df.index)
    unset = df["success"].isna() & ~errors
    if unset.any():
        problems.append((where, "success", "missing outside error episodes (termination 'error')",
                         list(df.index[unset])))
    df["success"] = df["success"].where(df["success"].notna(), False).astype(bool)
    key = df[list(EPISODE_KEY)].astype(str)
    dup = key.duplicated(keep=False)
    if dup.any():
        problems.append((where, "episode", "duplicate episode ids within one (task, embodiment, policy, channel)",
                         list(df.index[dup])))
    return df, problems


def load_records(paths) -> list[RecordsFile]:
    """Checked records files; raises RecordsError naming every file, column and rows at fault."""
    files, problems = [], []
    if not expand(paths):
        raise RecordsError([(", ".join(map(str, paths)) or "-", "-", "no .parquet or .csv records files found", [])])
    for path in expand(paths):
        where = str(path)
        if path.suffix not in SUFFIXES:
            problems.append((where, "-", f"expected a {' or '.join(SUFFIXES)} records file", []))
            continue
        if not path.is_file():
            problems.append((where, "-", "no such file", []))
            continue
        try:
            raw, provenance = _read(path)
        except Exception as exc:  # unreadable: report it beside the others
            problems.append((where, "-", f"unreadable ({type(exc).__name__}: {exc})", []))
            continue
        df, found = check(raw, where)
        problems += found
        if not found:
            for key, value in provenance.items():   # file-level metadata fills a column the rows lack
                if key not in df.columns:
                    df[key] = value
            df["_file"], df["_row"] = where, np.arange(len(df))
            files.append(RecordsFile(path, file_sha256(path), df, provenance))
    if not problems:
        problems += _duplicates_across(files)
    if problems:
        raise RecordsError(problems)
    return files


def _duplicates_across(files: list[RecordsFile]) -> list:
    if len(files) < 2:
        return []
    both = pd.concat([f.frame[[*EPISODE_KEY, "_file", "_row"]] for f in files], ignore_index=True)
    dup = both[list(EPISODE_KEY)].astype(str).duplicated(keep=False)
    problems = []
    for where, g in both[dup].groupby("_file", sort=True):
        problems.append((where, "episode", "episode ids also present in another file: "
                         + json.dumps(sorted(set(both[dup]["_file"]) - {where})), list(g["_row"])))
    return problems
