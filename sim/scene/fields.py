"""Checked numbers from task files: a bad value fails with the file, the field and what was expected."""

from __future__ import annotations

import math

from sim.errors import SpecError


def _describe(low, high, low_open: bool, integer: bool, unit: str) -> str:
    kind = "an integer" if integer else "a number"
    unit = f" {unit}" if unit else ""
    if low is not None and high is not None:
        return f"{kind} in {'(' if low_open else '['}{low}, {high}]{unit}"
    if low is not None:
        return f"{kind} {'>' if low_open else '>='} {low}{unit}"
    return kind + (f" ({unit.strip()})" if unit else "")


def number(path, field: str, value, low: float | None = None, high: float | None = None, *,
           low_open: bool = False, integer: bool = False, unit: str = "") -> float:
    """A finite number (an int when ``integer``) within [low, high]; ``low_open`` excludes low.
    ``unit`` is named in the error."""
    kinds = int if integer else (int, float)
    ok = isinstance(value, kinds) and not isinstance(value, bool) and math.isfinite(value)
    if ok and low is not None:
        ok = value > low if low_open else value >= low
    if ok and high is not None:
        ok = value <= high
    if not ok:
        raise SpecError(path, field, _describe(low, high, low_open, integer, unit), value)
    return int(value) if integer else float(value)


def num_list(path, field: str, value, length: int | None = None, positive: bool = False) -> tuple[float, ...]:
    """A list of ``length`` finite numbers (all > 0 when ``positive``)."""
    ok = isinstance(value, (list, tuple)) and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)
    if not ok or (length is not None and len(value) != length):
        raise SpecError(path, field, f"a list of {length or 'some'} numbers", value)
    if positive and any(v <= 0 for v in value):
        raise SpecError(path, field, "positive numbers", value)
    return tuple(float(v) for v in value)


# Sane physical bounds for task objects and links. Below a gram a body is too light for the 2 ms
# step against hands of a few hundred grams; the catalog's heaviest fixed base (a toilet) is 20 kg.
MASS_RANGE_KG = (0.001, 100.0)
# Sliding friction of real material pairs, from PTFE (~0.05) to rubber on a dry surface (~2).
FRICTION_RANGE = (0.05, 2.0)
# Rolling resistance length (MuJoCo's third friction coefficient); soft fruit is about 0.001 m.
ROLLING_FRICTION_RANGE_M = (0.0, 0.01)
# From foams and hollow shells (~10 kg/m^3) to the densest metals (~22,600 kg/m^3).
DENSITY_RANGE_KG_M3 = (10.0, 25000.0)
