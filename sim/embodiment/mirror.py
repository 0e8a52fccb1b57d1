"""Left/right mirroring of hand descriptions.

Hands are described for the right side. The left hand is its reflection through the hand's yz
plane, M = diag(-1, 1, 1):

* positions (body origins, geom centres, coms, sites, pad centres/normals/axes): p -> M p
* body / geom / site rotations: R -> M R M (a proper rotation again)
* hinge axes: a -> -M a, so that the same joint angle gives the mirrored pose and the joint
  limits stay the same (a rotation is a pseudo-vector: M R(a, q) M = R(-M a, q)).

In an attach-body frame of the left hand, a right-hand point p therefore sits at M p: the tactile
layer mirrors pad assets by negating x.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .frames import Transform
from .links import GeomSpec, JointSpec, LinkSpec

M = np.diag([-1.0, 1.0, 1.0])


def mirror_vec(v: np.ndarray) -> np.ndarray:
    return M @ np.asarray(v, float)


def mirror_rot(R: np.ndarray) -> np.ndarray:
    return M @ R @ M


def mirror_axis(a: np.ndarray) -> np.ndarray:
    return -(M @ np.asarray(a, float))


def mirror_transform(T: Transform) -> Transform:
    return Transform(mirror_vec(T.pos), mirror_rot(T.rot))


def mirror_geom(g: GeomSpec) -> GeomSpec:
    fromto = None
    if g.fromto is not None:
        fromto = np.concatenate([mirror_vec(g.fromto[:3]), mirror_vec(g.fromto[3:])])
    return dataclasses.replace(g, pos=mirror_vec(g.pos), rot=mirror_rot(g.rot), fromto=fromto)


def mirror_joint(j: JointSpec) -> JointSpec:
    return dataclasses.replace(j, axis=mirror_axis(j.axis))


def mirror_link(link: LinkSpec) -> LinkSpec:
    inertial = dataclasses.replace(link.inertial, com=mirror_vec(link.inertial.com))
    return dataclasses.replace(
        link,
        origin=mirror_transform(link.origin),
        joints=tuple(mirror_joint(j) for j in link.joints),
        geoms=tuple(mirror_geom(g) for g in link.geoms),
        inertial=inertial,
    )


def side_transform(T: Transform, side: str) -> Transform:
    return mirror_transform(T) if side == "left" else T


def side_links(links, side: str):
    return tuple(mirror_link(link) for link in links) if side == "left" else tuple(links)
