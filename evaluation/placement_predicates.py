"""Predicates on where objects are relative to containers, surfaces, points and zones: inside,
on_surface, within_distance, matched_within_distance, in_zone, relative_offset."""

from __future__ import annotations

import numpy as np

from evaluation.args import ArgReader
from evaluation.geometry import length, masked_distance, rotation, to_local, vertical_half_extent
from evaluation.grammar import Condition, register
from evaluation.state import TABLE
from evaluation.step import EvalStep

AXES = ("xy", "xyz", "z")


def point_of(s: EvalStep, name: str, offset: np.ndarray) -> np.ndarray:
    """World position of a point given in an object's frame."""
    o = s.obj(name)
    return np.asarray(o.pos, dtype=float) + rotation(o.quat) @ offset


@register("inside")
class Inside(Condition):
    """The object centre lies in the container's cavity box (object frame), grown by ``margin``
    (metres, scalar or [x, y, z]). ``box: {offset, half_extents}`` replaces the cavity, e.g. a shelf;
    ``object_offset`` tests a point of the object instead of its centre (a ladle's bowl)."""

    def __init__(self, a: ArgReader):
        self.object = a.object("object")
        self.object_offset = a.vector3("object_offset", [0.0, 0.0, 0.0])
        if a.has("box"):
            self.container = a.object("container")
            box = a.nested("box")
            self.offset, self.half = box.vector3("offset", [0.0, 0.0, 0.0]), box.vector3("half_extents")
            box.done()
        else:
            self.container = a.container("container")
            info = a.scope.context.objects[self.container]
            self.half = np.asarray(info.interior_half_extents, dtype=float)
            self.offset = np.zeros(3) if info.interior_offset is None else np.asarray(info.interior_offset, float)
        self.half = self.half + a.margin3("margin")

    def __call__(self, s: EvalStep) -> bool:
        c = s.obj(self.container)
        local = to_local(point_of(s, self.object, self.object_offset), c.pos, c.quat) - self.offset
        return bool((np.abs(local) <= self.half).all())


@register("on_surface")
class OnSurface(Condition):
    """The object rests on a surface object (or 'table'): its bounding-box bottom is between
    ``max_penetration`` below and ``max_height_above`` above the support height (the cavity floor of a
    container, else the top of the surface's box), and its centre is within ``max_dist_xy`` of the
    surface centre in xy (omitted: inside the surface's footprint). 'table' checks height only."""

    def __init__(self, a: ArgReader):
        self.object = a.object("object")
        self.surface = a.surface("surface")
        self.max_above = a.number("max_height_above", 0.03, lo=0.0)
        self.max_pen = a.number("max_penetration", 0.02, lo=0.0)
        self.max_xy = a.number("max_dist_xy", None, lo=0.0)
        if self.surface == TABLE and self.max_xy is not None:
            raise a.error("max_dist_xy", "no max_dist_xy with surface: table (use in_zone)", self.max_xy)
        if self.surface != TABLE:
            info = a.scope.context.objects[self.surface]
            self.half = np.asarray(info.half_extents, dtype=float)
            if info.interior_half_extents is not None:
                off = np.zeros(3) if info.interior_offset is None else np.asarray(info.interior_offset, float)
                self.floor = off - np.array([0.0, 0.0, float(info.interior_half_extents[2])])
            else:
                self.floor = None

    def _support(self, s: EvalStep) -> tuple[float, bool]:
        o = s.obj(self.object)
        if self.surface == TABLE:
            return s.state.table_height, True
        su = s.obj(self.surface)
        key = ("support_top", self.surface)     # half and floor follow from the surface alone
        top = s.memo.get(key)
        if top is None:
            if self.floor is None:
                top = su.pos[2] + vertical_half_extent(su.quat, self.half)
            else:
                top = (su.pos + rotation(su.quat) @ self.floor)[2]
            s.memo[key] = top
        if self.max_xy is None:
            ok_xy = bool((np.abs(to_local(o.pos, su.pos, su.quat)[:2]) <= self.half[:2]).all())
        else:
            ok_xy = masked_distance(o.pos, su.pos, "xy") <= self.max_xy
        return float(top), ok_xy

    def __call__(self, s: EvalStep) -> bool:
        top, ok_xy = self._support(s)
        o = s.obj(self.object)
        gap = o.pos[2] - vertical_half_extent(o.quat, s.info(self.object).half_extents) - top
        return ok_xy and -self.max_pen <= gap <= self.max_above


@register("within_distance")
class WithinDistance(Condition):
    """The object centre is within ``max_dist`` of a target object or point over ``axes``;
    ``offset`` shifts the target (target object's frame, or world for a point), ``object_offset``
    the tested point of the object (object frame)."""

    def __init__(self, a: ArgReader):
        self.object = a.object("object")
        self.object_offset = a.vector3("object_offset", [0.0, 0.0, 0.0])
        self.target = a.target("target")
        self.max_dist = a.number("max_dist", lo=0.0)
        self.axes = a.choice("axes", AXES, "xyz")
        self.offset = a.vector3("offset", [0.0, 0.0, 0.0])

    def __call__(self, s: EvalStep) -> bool:
        goal = s.target_pos(self.target, self.offset)
        return masked_distance(point_of(s, self.object, self.object_offset), goal, self.axes) <= self.max_dist


def _has_matching(ok: np.ndarray) -> bool:
    """Whether every row can take a distinct column with ok[row, col] (augmenting paths)."""
    owner = [-1] * ok.shape[1]

    def augment(row: int, seen: list[bool]) -> bool:
        for col in np.flatnonzero(ok[row]):
            if not seen[col]:
                seen[col] = True
                if owner[col] < 0 or augment(owner[col], seen):
                    owner[col] = row
                    return True
        return False

    return all(augment(r, [False] * ok.shape[1]) for r in range(ok.shape[0]))


@register("matched_within_distance")
class MatchedWithinDistance(Condition):
    """Each object is within ``max_dist`` of its own target (one-to-one assignment exists)."""

    def __init__(self, a: ArgReader):
        self.objects = a.objects("objects")
        self.targets = a.targets("targets")
        self.max_dist = a.number("max_dist", lo=0.0)
        self.axes = a.choice("axes", AXES, "xyz")
        if len(self.targets) < len(self.objects):
            raise a.error("targets", f"at least as many targets as objects ({len(self.objects)})", len(self.targets))

    def __call__(self, s: EvalStep) -> bool:
        goals = [s.target_pos(t) for t in self.targets]
        ok = np.array([[masked_distance(s.obj(o).pos, g, self.axes) <= self.max_dist for g in goals]
                       for o in self.objects])
        return _has_matching(ok)


@register("in_zone")
class InZone(Condition):
    """The object centre's world xy lies in a named zone (rectangle or disc)."""

    def __init__(self, a: ArgReader):
        self.object = a.object("object")
        self.zone = a.zone("zone")

    def __call__(self, s: EvalStep) -> bool:
        xy = np.asarray(s.obj(self.object).pos, dtype=float)[:2]
        if "xy_min" in self.zone:
            return bool((xy >= self.zone["xy_min"]).all() and (xy <= self.zone["xy_max"]).all())
        return float(length(xy - self.zone["center_xy"])) <= self.zone["radius"]


@register("relative_offset")
class RelativeOffset(Condition):
    """The object centre's offset from a reference along one axis lies in [min, max]; ``frame:
    reference`` measures it in the reference object's frame, ``world`` (default) in world axes."""

    def __init__(self, a: ArgReader):
        self.object = a.object("object")
        self.reference = a.target("reference")
        self.axis = "xyz".index(a.choice("axis", ("x", "y", "z")))
        self.lo = a.number("min", None)
        self.hi = a.number("max", None)
        self.frame = a.choice("frame", ("world", "reference"), "world")
        if self.lo is None and self.hi is None:
            raise a.error("min", "min and/or max")
        if self.frame == "reference" and self.reference.kind != "object":
            raise a.error("frame", "'world' when the reference is a point", self.frame)

    def __call__(self, s: EvalStep) -> bool:
        delta = np.asarray(s.obj(self.object).pos, float) - s.target_pos(self.reference)
        if self.frame == "reference":
            delta = rotation(s.obj(self.reference.name).quat).T @ delta
        v = delta[self.axis]
        return (self.lo is None or v >= self.lo) and (self.hi is None or v <= self.hi)
