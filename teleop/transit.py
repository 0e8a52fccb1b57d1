"""Transit: the hand (and what it carries) lifted over things in the way before moving across.

A person moving their hand from one place to the next does not sweep it through a bottle standing
in between: they raise it over the tallest thing in the way, move across and come down. The
scripted operator does the same when a straight move would pass too low: the hand's shape comes
from its kinematics and link geoms (teleop/pinch_grasp.py's hand model, at the hand targets of the
move), the objects' from their geoms in the scene, at the places earlier steps planned for them.
A move with nothing in the way is left a single straight keyframe.
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass

import mujoco
import numpy as np

from sim.embodiment.mirror import M
from teleop.operator_motion import slerp
from teleop.pinch_grasp import hand_kinematics

CLEARANCE_M = 0.03            # the hand's (or carried object's) lowest point this far above a top in the way
SIDE_MARGIN_M = 0.02          # ... passing within this far of an object's side counts as over it
PATH_SAMPLES = 25             # points along the straight move that are checked
# support directions (link frame) whose extreme points outline each hand geom
_DIRECTIONS = np.array([d for d in itertools.product((-1.0, 0.0, 1.0), repeat=3) if any(d)], float)
_DIRECTIONS /= np.linalg.norm(_DIRECTIONS, axis=1, keepdims=True)


@dataclass(frozen=True)
class Obstacle:
    """One geom of an object: its bounding box (geom frame), or for a round geom standing upright
    a cylinder, and its highest point."""
    name: str
    centre: np.ndarray      # of the box (world)
    rot: np.ndarray         # box axes (world, columns)
    half: np.ndarray        # box half sizes; for an upright round geom (radius, radius, half height)
    disc: bool
    top: float              # world z

    def near(self, points: np.ndarray) -> np.ndarray:
        """Which ``points`` (n, 3, world) are inside it or within SIDE_MARGIN_M of its sides and
        CLEARANCE_M above its top (or below its bottom)."""
        local = (points - self.centre) @ self.rot
        margin = np.array([SIDE_MARGIN_M, SIDE_MARGIN_M, CLEARANCE_M])
        if self.disc:
            return ((np.linalg.norm(local[:, :2], axis=1) < self.half[0] + SIDE_MARGIN_M)
                    & (np.abs(local[:, 2]) < self.half[2] + CLEARANCE_M))
        return np.all(np.abs(local) < self.half + margin, axis=1)


@functools.lru_cache(maxsize=None)
def _hand_outline(hand_name: str, q: tuple[float, ...]) -> np.ndarray:
    """(n, 3) points outlining the right hand's link geoms at actuator targets ``q``, in the
    wrist-site frame: each geom's extreme point along 26 directions."""
    kin = hand_kinematics(hand_name)
    kin.points(np.asarray(q, float))                    # sets the configuration
    site = kin.hand.wrist_site
    points = []
    for link in kin.hand.links:
        body = kin.model.body(link.name).id
        R, p = kin.data.xmat[body].reshape(3, 3), kin.data.xpos[body]
        for geom in link.geoms:
            points.extend(p + R @ geom.support(u) for u in _DIRECTIONS)
    out = site.to_local(np.array(points))
    out.flags.writeable = False         # cached: shared by every caller
    return out


def hand_outline(hand_name: str, side: str, *targets: np.ndarray) -> np.ndarray:
    """The hand's outline (wrist-site frame) at each of the hand ``targets``, together; mirrored
    for the left hand."""
    pts = np.concatenate([_hand_outline(hand_name, tuple(np.round(q, 6))) for q in targets])
    return pts @ M if side == "left" else pts


def _geom_corners(model: mujoco.MjModel, data: mujoco.MjData, g: int) -> np.ndarray:
    centre, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
    signs = np.array(list(itertools.product((-1.0, 1.0), repeat=3)))
    R = data.geom_xmat[g].reshape(3, 3)
    return data.geom_xpos[g] + (centre + signs * half) @ R.T


def _box_faces(half: np.ndarray, spacing: float) -> np.ndarray:
    """Points on the faces of a box of half sizes ``half`` (its frame), corners included, at most
    ``spacing`` apart along each axis."""
    counts = [max(2, int(np.ceil(2 * h / spacing)) + 1) for h in half]
    index = np.stack(np.meshgrid(*(np.arange(n) for n in counts), indexing="ij"), axis=-1).reshape(-1, 3)
    on_face = np.any((index == 0) | (index == np.array(counts) - 1), axis=1)
    return -half + index[on_face] * (2 * half / (np.array(counts) - 1))


def object_geoms(model: mujoco.MjModel, body: int) -> list[int]:
    """The geoms of object ``body`` and of the links attached to it."""
    return [g for g in range(model.ngeom) if model.body_rootid[model.geom_bodyid[g]] == body]


def bounding_box_points(model: mujoco.MjModel, data: mujoco.MjData, body: int) -> np.ndarray:
    """Points on the faces of the bounding boxes of the object's geoms (world, as in ``data``),
    corners included and at most 2 SIDE_MARGIN_M apart: a long object carried across a thin one
    cannot pass it between two points unseen."""
    points = []
    for g in object_geoms(model, body):
        R = data.geom_xmat[g].reshape(3, 3)
        local = model.geom_aabb[g, :3] + _box_faces(model.geom_aabb[g, 3:], 2 * SIDE_MARGIN_M)
        points.append(data.geom_xpos[g] + local @ R.T)
    return np.concatenate(points)


def _turns(model: mujoco.MjModel, body: int, turned: dict[int, tuple[np.ndarray, np.ndarray]]) -> list:
    """The turns (anchor, rotation) that move body ``body``: its own link's and those of the links it
    hangs from (a door's handle swings with the door), innermost first."""
    chain = []
    while body > 0:
        if body in turned:
            chain.append(turned[body])
        body = int(model.body_parentid[body])
    return chain


def _turn_points(points: np.ndarray, chain: list) -> np.ndarray:
    for anchor, turn in chain:
        points = anchor + (points - anchor) @ turn.T
    return points


def obstacles(model: mujoco.MjModel, data: mujoco.MjData, name: str, body: int, shift: np.ndarray,
              turned: dict[int, tuple[np.ndarray, np.ndarray]]) -> list[Obstacle]:
    """The geoms of object ``name`` moved by ``shift`` from where ``data`` has them; those of a link
    body in ``turned``, or hanging from one, first turned about the hinges (anchor, rotation: world)."""
    out = []
    for g in object_geoms(model, body):
        chain = _turns(model, int(model.geom_bodyid[g]), turned)
        corners = _turn_points(_geom_corners(model, data, g), chain) + shift
        R = data.geom_xmat[g].reshape(3, 3)
        for _, turn in chain:
            R = turn @ R
        round_ = model.geom_type[g] in (mujoco.mjtGeom.mjGEOM_CYLINDER, mujoco.mjtGeom.mjGEOM_SPHERE,
                                        mujoco.mjtGeom.mjGEOM_CAPSULE)
        disc = bool(round_ and abs(R[2, 2]) > 0.99)
        half = model.geom_aabb[g, 3:].copy()
        centre = _turn_points(data.geom_xpos[g], chain) + R @ model.geom_aabb[g, :3] + shift
        if disc:
            half[:2] = model.geom_size[g, 0]
        out.append(Obstacle(name, centre, R, half, disc, float(corners[:, 2].max())))
    return out


def transit_height(start: np.ndarray, start_quat: np.ndarray, end: np.ndarray, end_quat: np.ndarray,
                   outline: np.ndarray, carried: np.ndarray | None, obstacles: list[Obstacle]) -> float | None:
    """The wrist height at which the move ``start`` -> ``end`` passes CLEARANCE_M over every
    obstacle it would hit going straight: a point of the hand (``outline``, wrist-site frame,
    turning from ``start_quat`` to ``end_quat`` as the move does) or of the carried object
    (``carried``: points from the wrist, world) below its top, over it or within SIDE_MARGIN_M of
    its side. None when the straight move hits nothing (passing over a top with less than
    CLEARANCE_M to spare is not a hit: it is where the hand already went in working demonstrations),
    and obstacles the hand is over where it arrives do not count: it comes down to them anyway."""
    R = np.zeros(9)

    def points(s: float) -> tuple[np.ndarray, np.ndarray]:
        wrist = start + s * (end - start)
        mujoco.mju_quat2Mat(R, slerp(start_quat, end_quat, s))
        rel = outline @ R.reshape(3, 3).T
        if carried is not None:
            rel = np.concatenate([rel, carried])
        return wrist, wrist + rel

    arrived = points(1.0)[1]
    obstacles = [ob for ob in obstacles if not ob.near(arrived).any()]
    need, hit = -np.inf, False
    for s in np.linspace(0.0, 1.0, PATH_SAMPLES):
        wrist, pts = points(s)
        for ob in obstacles:
            over = ob.near(pts)
            if over.any():
                lowest = pts[over, 2].min()
                hit |= lowest < ob.top
                need = max(need, wrist[2] + ob.top + CLEARANCE_M - lowest)
    return float(need) if hit else None
