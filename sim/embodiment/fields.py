"""Errors of the robot description files, and the field-path helpers of the blocks that are checked
against the rest of their hand (tactile, real_model, retarget) rather than by the per-file schema."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

from sim.errors import SpecError


class DescriptionError(SpecError):
    """An arm, hand or embodiment file is missing a field or holds a value of the wrong shape.

    A SpecError (whoever catches those catches these); built like one, ``(path, field, expected, got)``,
    or from one finished message ``"<file>: field '<field>': ..."``."""

    def __init__(self, path_or_message, field: str | None = None, expected: str | None = None, got=None):
        if field is None:
            ValueError.__init__(self, path_or_message)
            self.path = self.field = self.expected = None
        else:
            super().__init__(path_or_message, field, expected, got)


def _expected_error(path, where: str, expected: str, got=None) -> DescriptionError:
    return DescriptionError(path, where, expected, got)


class _Ctx:
    """Carries the file path and a field path for error messages.

    ``error(path, field, expected, got)`` builds what ``expect`` raises (the tactile layer passes its
    ``TactileSpecError``); the message reads the same either way.
    """

    def __init__(self, path: Path | str | None, where: str = "", error: Callable = _expected_error):
        self.path = path
        self.where = where
        self.error = error

    def sub(self, key) -> "_Ctx":
        return _Ctx(self.path, f"{self.where}.{key}" if self.where else str(key), self.error)

    def fail(self, msg: str):
        raise DescriptionError(f"{self.path}: field '{self.where}': {msg}")

    def expect(self, expected: str, got=None):
        raise self.error(self.path, self.where, expected, got)


def _get(d: dict, key: str, ctx: _Ctx, default=Ellipsis):
    if not isinstance(d, dict):
        ctx.fail(f"expected a mapping, got {type(d).__name__}")
    if key not in d:
        if default is Ellipsis:
            ctx.sub(key).fail("missing")
        return default
    return d[key]


def _is_number(x) -> bool:
    """A YAML number: not a quoted one ("12"), not a boolean."""
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _vec(v, n: int, ctx: _Ctx) -> np.ndarray:
    if not isinstance(v, (list, tuple)) or not all(_is_number(x) for x in v):
        ctx.fail(f"expected a list of {n} numbers, got {v!r}")
    a = np.asarray([float(x) for x in v], dtype=float)
    if not np.all(np.isfinite(a)):
        ctx.fail(f"expected a list of {n} finite numbers, got {v!r}")
    if a.shape != (n,):
        ctx.fail(f"expected a list of {n} numbers, got {len(a)}")
    return a


def _num(v, ctx: _Ctx, positive: bool = False) -> float:
    if not _is_number(v) or not np.isfinite(v):
        ctx.fail(f"expected a number, got {v!r}")
    x = float(v)
    if positive and not x > 0:
        ctx.fail(f"expected a positive number, got {x}")
    return x
