"""Object geometry as parts, and the generated shapes built from them.

A task object (or one link of an articulated object) is a list of parts placed in the object's
frame: MuJoCo primitives, or the convex hull of a mesh file. Physics collides the parts; the
tactile layer ray-casts against the same compiled geoms (`tactile.targets`). Generated shapes
expand into primitives:

    {shape: box, size: [hx, hy, hz], pos: [x, y, z], euler_deg: [rx, ry, rz], rgba: [...]}
    {open_box: {size: [hx, hy, hz], wall: 0.01, open: +z}}      # tray, crate, cabinet (open: -y)
    {open_cylinder: {size: [r, hz], wall: 0.006, segments: 16}}  # cup, bowl, pot, can
    {mesh: {file: mug.obj, scale: 0.001}}                         # a mesh file's convex hull (mesh_files)
Sizes are MuJoCo half sizes. Generated shapes also know their cavity (the `inside` predicate's box).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import mujoco
import numpy as np

from sim.schema.object_parts import PartEntry
from sim.scene.mesh_files import MeshRef, load_hull, parse_mesh

GEOM_TYPES = {
    "box": mujoco.mjtGeom.mjGEOM_BOX, "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
    "sphere": mujoco.mjtGeom.mjGEOM_SPHERE, "ellipsoid": mujoco.mjtGeom.mjGEOM_ELLIPSOID,
    "capsule": mujoco.mjtGeom.mjGEOM_CAPSULE, "mesh": mujoco.mjtGeom.mjGEOM_MESH,
}


@dataclass(frozen=True)
class Part:
    shape: str
    size: tuple[float, ...]
    pos: tuple[float, float, float] = (0.0, 0.0, 0.0)
    quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    rgba: tuple[float, float, float, float] | None = None   # None: the object's colour
    mesh: MeshRef | None = None     # shape "mesh": the file; size is then the hull's half extents

    @property
    def volume(self) -> float:
        if self.mesh is not None:
            return float(load_hull(self.mesh).volume)
        s = self.size
        return {"box": lambda: 8 * s[0] * s[1] * s[2], "sphere": lambda: 4 / 3 * math.pi * s[0] ** 3,
                "ellipsoid": lambda: 4 / 3 * math.pi * s[0] * s[1] * s[2],
                "cylinder": lambda: 2 * math.pi * s[0] ** 2 * s[1],
                "capsule": lambda: math.pi * s[0] ** 2 * (2 * s[1] + 4 / 3 * s[0])}[self.shape]()

    def local_half_extents(self) -> np.ndarray:
        s = self.size
        return np.array({"box": (s[0], s[1], s[2]) if len(s) == 3 else (0, 0, 0), "cylinder": (s[0], s[0], s[-1]),
                         "sphere": (s[0],) * 3, "ellipsoid": tuple(s[:3]) if len(s) == 3 else (0, 0, 0),
                         "capsule": (s[0], s[0], s[-1] + s[0]), "mesh": tuple(s)}[self.shape], dtype=float)

    def aabb(self, pos=(0.0, 0.0, 0.0), quat=(1.0, 0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
        """Axis-aligned box of the part's local box, in a frame where its parent sits at pos/quat."""
        rot = quat_matrix(quat) @ quat_matrix(self.quat)
        centre = np.asarray(pos, float) + quat_matrix(quat) @ np.asarray(self.pos, float)
        half = np.abs(rot) @ self.local_half_extents()
        return centre - half, centre + half


@dataclass(frozen=True)
class Cavity:
    half_extents: tuple[float, float, float]
    offset: tuple[float, float, float]


def quat_matrix(quat) -> np.ndarray:
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, np.asarray(quat, dtype=float))
    return mat.reshape(3, 3)


def euler_quat(euler_deg) -> tuple[float, float, float, float]:
    quat = np.zeros(4)
    mujoco.mju_euler2Quat(quat, np.deg2rad(np.asarray(euler_deg, dtype=float)), "xyz")
    return tuple(float(v) for v in quat)


def pad_size(size) -> list[float]:
    return [float(v) for v in size] + [0.0] * (3 - len(size))


# ---------------------------------------------------------------- generated shapes


def _axis(open_side: str) -> tuple[int, float]:
    return "xyz".index(open_side[1]), (1.0 if open_side[0] == "+" else -1.0)


def open_box(size, wall: float, open_side: str = "+z") -> tuple[list[Part], Cavity]:
    """A box with one open face: five slabs of thickness `wall` inside the outer half size."""
    half = np.asarray(size, float)
    open_axis, open_sign = _axis(open_side)
    parts = []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            if axis == open_axis and sign == open_sign:
                continue
            slab = half.copy()
            slab[axis] = wall / 2
            pos = np.zeros(3)
            pos[axis] = sign * (half[axis] - wall / 2)
            # side slabs stop at the slabs across them so no two slabs overlap
            for other in range(3):
                if other != axis and other < axis:
                    slab[other] = half[other] - wall
            parts.append(Part("box", tuple(slab.round(6)), tuple(pos.round(6))))
    cavity_half = half - wall
    offset = np.zeros(3)
    cavity_half[open_axis] = half[open_axis] - wall / 2
    offset[open_axis] = open_sign * wall / 2
    return parts, Cavity(tuple(cavity_half.round(6)), tuple(offset.round(6)))


def open_cylinder(size, wall: float, segments: int = 16) -> tuple[list[Part], Cavity]:
    """An open-top cylinder: a floor disc and `segments` wall slabs on a polygon round the axis."""
    radius, half_h = float(size[0]), float(size[1])
    parts = [Part("cylinder", (radius, wall / 2), (0.0, 0.0, -half_h + wall / 2))]
    mid = radius - wall / 2
    # slab half width covering the polygon edge, slightly overlapping its neighbours at the corners
    half_w = mid * math.tan(math.pi / segments) + wall / 2
    wall_h = half_h - wall / 2
    for k in range(segments):
        a = 2 * math.pi * k / segments
        parts.append(Part("box", (wall / 2, round(half_w, 6), round(wall_h, 6)),
                          (round(mid * math.cos(a), 6), round(mid * math.sin(a), 6), round(wall / 2, 6)),
                          euler_quat([0, 0, math.degrees(a)])))
    inner = (radius - wall) / math.sqrt(2)   # the square inscribed in the inner wall: never outside it
    return parts, Cavity((round(inner, 6),) * 2 + (round(half_h - wall / 2, 6),),
                         (0.0, 0.0, round(wall / 2, 6)))


# ---------------------------------------------------------------- parsing


def _transform(parts: list[Part], pos, quat) -> list[Part]:
    rot = quat_matrix(quat)
    out = []
    for p in parts:
        q = np.zeros(4)
        mujoco.mju_mulQuat(q, np.asarray(quat, float), np.asarray(p.quat, float))
        out.append(replace(p, pos=tuple((np.asarray(pos) + rot @ np.asarray(p.pos)).round(6).tolist()),
                           quat=tuple(float(v) for v in q)))
    return out


def _generated(entry: PartEntry) -> tuple[list[Part], Cavity]:
    """An open box or open cylinder in its own frame."""
    if entry.open_box is not None:
        box = entry.open_box
        return open_box(box.size, box.wall, box.open)
    cylinder = entry.open_cylinder
    return open_cylinder(cylinder.size, cylinder.wall, cylinder.segments)


def build_part(path, field: str, entry: PartEntry) -> tuple[list[Part], Cavity | None]:
    """One entry of a `parts` list (checked by its schema): a primitive, a generated shape (several
    primitives) or a mesh; ``path`` and ``field`` name a mesh file that cannot be read."""
    pos = tuple(float(v) for v in entry.pos)
    quat = euler_quat(entry.euler_deg)
    rgba = tuple(float(v) for v in entry.rgba) if entry.rgba is not None else None
    if entry.open_box is not None or entry.open_cylinder is not None:
        parts, cavity = _generated(entry)
        parts = [replace(p, rgba=rgba) for p in _transform(parts, pos, quat)]
        if quat != (1.0, 0.0, 0.0, 0.0):
            cavity = None    # a turned cavity is not axis-aligned with the object: declare it
        else:
            cavity = Cavity(cavity.half_extents, tuple(float(a + b) for a, b in zip(cavity.offset, pos)))
        return parts, cavity
    if entry.mesh is not None:
        ref = parse_mesh(path, f"{field}.mesh", entry.mesh)
        half = tuple(float(v) for v in (load_hull(ref).extents / 2).round(6))
        return [Part("mesh", half, pos, quat, rgba, ref)], None
    return [Part(entry.shape, tuple(float(v) for v in entry.size), pos, quat, rgba)], None


def build_parts(path, field: str, entries: list[PartEntry]) -> tuple[tuple[Part, ...], Cavity | None]:
    """A `parts` list; the cavity is that of its single generated shape, if it has exactly one."""
    parts, cavities = [], []
    for i, entry in enumerate(entries):
        p, cavity = build_part(path, f"{field}[{i}]", entry)
        parts += p
        if cavity is not None:
            cavities.append(cavity)
    return tuple(parts), (cavities[0] if len(cavities) == 1 else None)


# ---------------------------------------------------------------- bounds and masses


def parts_aabb(parts, pos=(0.0, 0.0, 0.0), quat=(1.0, 0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    boxes = [p.aabb(pos, quat) for p in parts]
    return np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0)


def part_masses(parts, total_mass: float) -> list[float]:
    """The object's mass shared over its parts by volume (uniform density)."""
    volumes = np.array([p.volume for p in parts])
    return (total_mass * volumes / volumes.sum()).tolist()
