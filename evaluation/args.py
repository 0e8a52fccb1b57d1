"""Reading and checking one predicate's YAML arguments against the task context.

Every check raises TaskSpecError with the field path (``metrics.stages[2].predicate.inside.container``)
and the valid names, so a task file can be fixed without reading Python.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from evaluation.condition import Condition, ConditionCompiler
from evaluation.errors import TaskSpecError, one_of
from evaluation.state import TABLE
from evaluation.step import Target

REQUIRED = object()
CONTACT_NAMES = ("table", "left_hand", "right_hand", "any_hand")


class ArgReader:
    """Typed access to a predicate's argument mapping; ``done()`` rejects unknown arguments."""

    def __init__(self, predicate: str, raw: Any, scope: ConditionCompiler, path: str):
        self.predicate, self.scope, self.path = predicate, scope, path
        if raw is None:
            raw = {}
        if not isinstance(raw, Mapping):
            raise self._err(path, f"a mapping of {predicate} arguments", raw)
        self.raw = dict(raw)
        self.known: list[str] = []

    # -- plumbing -------------------------------------------------------------------------------
    def _err(self, field: str, expected: str, got: Any = None) -> TaskSpecError:
        return TaskSpecError(field, expected, got, self.scope.source)

    def error(self, name: str, expected: str, got: Any = None) -> TaskSpecError:
        return self._err(f"{self.path}.{name}", expected, got)

    def has(self, name: str) -> bool:
        """Whether an optional argument is given (it is then a known argument name)."""
        self.known.append(name)
        return name in self.raw

    def _get(self, name: str, default: Any) -> Any:
        self.known.append(name)
        if name in self.raw:
            return self.raw[name]
        if default is REQUIRED:
            raise self.error(name, f"a value (required argument of {self.predicate})")
        return default

    def done(self) -> None:
        for name in self.raw:
            if name not in self.known:
                raise self.error(name, f"an argument of {self.predicate}: {one_of(set(self.known))}")

    def _names(self, name: str, value: Any, valid: Sequence[str], what: str) -> str:
        if not isinstance(value, str) or value not in valid:
            raise self.error(name, f"{what} {one_of(valid)}".strip(), value)
        return value

    def _list(self, name: str, default: Any) -> list[tuple[str, Any]]:
        value = self._get(name, default)
        if not isinstance(value, list) or not value:
            raise self.error(name, "a non-empty list", value)
        return [(f"{name}[{i}]", v) for i, v in enumerate(value)]

    # -- scalars --------------------------------------------------------------------------------
    def number(self, name: str, default: Any = REQUIRED, lo: float | None = None, hi: float | None = None):
        value = self._get(name, default)
        if value is None and default is None:
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.error(name, "a finite number", value)
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            bounds = [f">= {lo}"] * (lo is not None) + [f"<= {hi}"] * (hi is not None)
            raise self.error(name, "a number " + " and ".join(bounds), value)
        return float(value)

    def integer(self, name: str, default: Any = REQUIRED, lo: int = 1) -> int:
        value = self._get(name, default)
        if isinstance(value, bool) or not isinstance(value, int) or value < lo:
            raise self.error(name, f"an integer >= {lo}", value)
        return value

    def flag(self, name: str, default: bool) -> bool:
        value = self._get(name, default)
        if not isinstance(value, bool):
            raise self.error(name, "true or false", value)
        return value

    def choice(self, name: str, choices: Sequence[str], default: Any = REQUIRED) -> str | None:
        value = self._get(name, default)
        if value is None and default is None:
            return None
        return self._names(name, value, choices, "")

    def vector3(self, name: str, default: Any = REQUIRED, unit: bool = False) -> np.ndarray:
        value = self._get(name, default)
        ok = isinstance(value, (list, tuple, np.ndarray)) and len(value) == 3
        ok = ok and all(not isinstance(v, bool) and isinstance(v, (int, float, np.floating)) for v in value)
        if not ok or not np.all(np.isfinite(np.asarray(value, dtype=float))):
            raise self.error(name, "a list of 3 finite numbers", value)
        vec = np.asarray(value, dtype=float)
        if unit:
            if np.linalg.norm(vec) == 0:
                raise self.error(name, "a non-zero axis", value)
            vec = vec / np.linalg.norm(vec)
        return vec

    def margin3(self, name: str, default: float = 0.0) -> np.ndarray:
        """A scalar or per-axis [x, y, z] non-negative margin."""
        value = self.raw.get(name, default)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            self.number(name, default, lo=0.0)
            return np.full(3, float(value))
        vec = self.vector3(name, default)
        if np.any(vec < 0):
            raise self.error(name, "non-negative margins", value)
        return vec

    # -- names from the context -----------------------------------------------------------------
    def object(self, name: str, default: Any = REQUIRED) -> str:
        return self._names(name, self._get(name, default), list(self.scope.context.objects), "an object")

    def objects(self, name: str, default: Any = REQUIRED) -> list[str]:
        valid = list(self.scope.context.objects)
        if default is not REQUIRED and name not in self.raw:
            self.known.append(name)
            return list(default)
        return [self._names(f, v, valid, "an object") for f, v in self._list(name, REQUIRED)]

    def container(self, name: str) -> str:
        obj = self.object(name)
        if self.scope.context.objects[obj].interior_half_extents is None:
            valid = [n for n, i in self.scope.context.objects.items() if i.interior_half_extents is not None]
            raise self.error(name, f"an object with interior_half_extents (containers: {one_of(valid)})", obj)
        return obj

    def surface(self, name: str) -> str:
        value = self._get(name, REQUIRED)
        return self._names(name, value, [TABLE, *self.scope.context.objects], "an object or 'table':")

    def contact_name(self, name: str) -> str:
        value = self._get(name, REQUIRED)
        return self._names(name, value, [*CONTACT_NAMES, *self.scope.context.objects], "an object or")

    def _target(self, field: str, value: Any) -> Target:
        ctx = self.scope.context
        if isinstance(value, str) and value in ctx.objects and value in ctx.points:
            raise self._err(f"{self.path}.{field}", "a name that is not both an object and a point", value)
        if isinstance(value, str) and value in ctx.objects:
            return Target("object", value)
        if isinstance(value, str) and value in ctx.points:
            return Target("point", value)
        expected = f"an object {one_of(ctx.objects)} or a point {one_of(ctx.points)}"
        raise self._err(f"{self.path}.{field}", expected, value)

    def target(self, name: str) -> Target:
        return self._target(name, self._get(name, REQUIRED))

    def targets(self, name: str) -> list[Target]:
        return [self._target(f, v) for f, v in self._list(name, REQUIRED)]

    def zone(self, name: str) -> dict:
        """A context zone as {xy_min, xy_max} or {center_xy, radius} with numpy values."""
        zones = self.scope.context.zones
        zone = zones[self._names(name, self._get(name, REQUIRED), list(zones), "a zone")]
        try:
            if set(zone) >= {"xy_min", "xy_max"}:
                out = {k: np.asarray(zone[k], dtype=float).reshape(2) for k in ("xy_min", "xy_max")}
            else:
                out = {"center_xy": np.asarray(zone["center_xy"], dtype=float).reshape(2),
                       "radius": float(zone["radius"])}
        except (KeyError, TypeError, ValueError):
            raise self.error(name, "a context zone with xy_min/xy_max or center_xy/radius (2 numbers each, "
                             "radius a number)", zone) from None
        return out

    def _joint(self, field: str, value: Any) -> str:
        ctx = self.scope.context
        if ctx.joints is not None:
            if not isinstance(value, str) or value not in ctx.joints:
                raise self._err(f"{self.path}.{field}", f"a joint {one_of(ctx.joints)}", value)
            return value
        if not isinstance(value, str) or value.count("/") != 1 or value.split("/")[0] not in ctx.objects:
            raise self._err(f"{self.path}.{field}", f"'object/joint' with object {one_of(ctx.objects)}", value)
        return value

    def joint(self, name: str) -> str:
        return self._joint(name, self._get(name, REQUIRED))

    def joints(self, name: str) -> list[str]:
        return [self._joint(f, v) for f, v in self._list(name, REQUIRED)]

    def nested(self, name: str) -> ArgReader:
        """A mapping-valued argument read with its own reader (call its ``done()``)."""
        return ArgReader(f"{self.predicate}.{name}", self._get(name, REQUIRED), self.scope, f"{self.path}.{name}")

    # -- nested conditions ----------------------------------------------------------------------
    def conditions(self, name: str) -> list[Condition]:
        return [self.scope.compile(v, f"{self.path}.{f}") for f, v in self._list(name, REQUIRED)]
