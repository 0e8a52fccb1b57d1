"""Schema of a `pick`'s waypoints (`via`, `via_times`, `via_point`) and `hold` (teleop/plan_steps/via.py).

`via: [{inside: <container>}, {over: <object>}, ...]` takes the carried object's `via_point` (object frame,
default its centre) into a container's cavity, or over an object, in order, `via_times` rounds, before it
goes to `place` (a ladle dipped into a pot, then over a bowl, twice). Each stop may shift its spot by
`offset` [dx, dy] or [dx, dy, dz] (metres, world). The checks run as `PickStep` field validators, with the
task's objects as validation context (sim/schema/demo_plan.py).
"""

from __future__ import annotations

from .base import is_number

VIA_KINDS = ("inside", "over")      # into a container's cavity, below its rim; above an object, clear of its top
VIA_TIMES_RANGE = (1, 10)


def check_via(via, *, picked: str | None, objects: dict) -> list[dict]:
    """`via` if it is a non-empty list of stops {inside: <container> | over: <object>, [offset]} naming
    other objects than the picked one; else ValueError saying what was expected."""
    names = sorted(n for n in objects if n != picked)
    containers = [n for n in names if objects[n].interior_half_extents is not None]
    expected = (f"a non-empty list of stops {{inside: <container from {containers}>}} or {{over: <object from "
                f"{names}>}}, each with an optional offset [dx, dy] or [dx, dy, dz]")
    if not isinstance(via, list) or not via:
        raise ValueError(expected)
    for i, stop in enumerate(via):
        kinds = [k for k in VIA_KINDS if isinstance(stop, dict) and k in stop]
        if len(kinds) != 1 or set(stop) - {*VIA_KINDS, "offset"}:
            raise ValueError(f"{expected} (stop {i}: {stop!r})")
        kind = kinds[0]
        allowed = containers if kind == "inside" else names
        if stop[kind] not in allowed:
            raise ValueError(f"stop {i}: {kind}: one of {allowed}, got {stop[kind]!r}")
        offset = stop.get("offset", [0.0, 0.0])
        if not isinstance(offset, list) or len(offset) not in (2, 3) or not all(map(is_number, offset)):
            raise ValueError(f"stop {i}: offset: [dx, dy] or [dx, dy, dz] in metres, got {offset!r}")
    return via
