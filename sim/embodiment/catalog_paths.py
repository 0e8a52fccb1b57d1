"""Where the arm, hand and embodiment files live, and reading one through its schema."""

from __future__ import annotations

from pathlib import Path
from typing import TypeVar

from pydantic import BaseModel

from sim.schema import load

from .fields import DescriptionError

CATALOG_DIR = Path(__file__).resolve().parent.parent / "catalog"
ARMS_DIR = CATALOG_DIR / "arms"
HANDS_DIR = CATALOG_DIR / "hands"
EMBODIMENTS_DIR = CATALOG_DIR / "embodiments"
_FOLDERS = {"arm": "ARMS_DIR", "hand": "HANDS_DIR", "embodiment": "EMBODIMENTS_DIR"}

M = TypeVar("M", bound=BaseModel)


def folder(kind: str) -> Path:
    """The folder of one kind, read at call time (tests point it at an edited copy)."""
    return globals()[_FOLDERS[kind]]


def file_names(kind: str) -> list[str]:
    return sorted(p.stem for p in folder(kind).glob("*.yaml"))


def resolve(kind: str, name: str) -> Path:
    path = folder(kind) / f"{name}.yaml"
    if not path.is_file():
        raise ValueError(f"unknown {kind} {name!r}; valid: {', '.join(file_names(kind))}")
    return path


def read_file(model: type[M], path: Path) -> tuple[dict, M]:
    """The raw mapping and its validated model; schema findings are DescriptionErrors naming file and field."""
    return load(model, path, error=DescriptionError)
