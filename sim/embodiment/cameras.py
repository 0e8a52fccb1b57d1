"""The six robot cameras: chest, overhead, stereo_left, stereo_right, left_wrist, right_wrist.

MuJoCo cameras look along their local -z with +y up in the image. Poses are given as a position and
a look-at target (world, or the hand frame for wrist cameras); the embodiment file may override the
defaults below (``cameras: {name: {pos, target, fovy}}``).
"""

from __future__ import annotations

import mujoco
import numpy as np

from .description import EmbodimentDescription, Transform, mat_to_quat
from .mirror import mirror_vec

TABLE_CENTRE = np.array([0.0, 0.05, 0.75])
STEREO_BASELINE_M = 0.06
DEFAULTS = {
    "chest": (np.array([0.0, -0.50, 1.25]), np.array([0.0, 0.05, 0.75])),
    "overhead": (np.array([0.0, 0.05, 1.95]), np.array([0.0, 0.05, 0.75])),
    "stereo": (np.array([0.0, 0.95, 1.40]), np.array([0.0, 0.0, 0.78])),   # centre of the pair
    # right hand frame: on the palm side of the wrist, looking along the fingers, tilted to the palm
    "wrist": (np.array([0.0, 0.05, 0.0]), np.array([0.0, 0.09, 0.2])),
}


def look_at(pos, target, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """Camera rotation (columns x right, y up, z backwards) looking from ``pos`` at ``target``."""
    d = np.asarray(target, float) - np.asarray(pos, float)
    d /= np.linalg.norm(d)
    up = np.asarray(up, float)
    x = np.cross(d, up)
    if np.linalg.norm(x) < 1e-6:               # looking along `up`: pick image-up = +y world
        x = np.cross(d, np.array([0.0, 1.0, 0.0]))
    x /= np.linalg.norm(x)
    z = -d
    y = np.cross(z, x)
    return np.column_stack([x, y, z])


def _add(body: mujoco.MjsBody, name: str, pos, rot, fovy: float) -> None:
    body.add_camera(name=name, pos=np.asarray(pos, float), quat=mat_to_quat(rot), fovy=float(fovy))


def add_cameras(emb: EmbodimentDescription, world: mujoco.MjsBody, torso: mujoco.MjsBody,
                torso_tf: Transform, palms: dict[str, mujoco.MjsBody]) -> list[str]:
    cams = emb.cameras

    def pose(name, key):
        pos, target = DEFAULTS[key]
        c = cams[name]
        return (c.pos if c.pos is not None else pos), (c.target if c.target is not None else target)

    # chest: rigidly on the torso, looking at the table
    pos, target = pose("chest", "chest")
    R = look_at(pos, target)
    inv = torso_tf.inverse()
    _add(torso, "chest", inv.pos + inv.rot @ pos, inv.rot @ R, cams["chest"].fovy)
    # overhead: straight down, image up = +y (away from the robot)
    pos, target = pose("overhead", "overhead")
    _add(world, "overhead", pos, look_at(pos, target, up=(0.0, 1.0, 0.0)), cams["overhead"].fovy)
    # stereo pair: parallel optical axes, baseline along the camera x axis
    centre, target = DEFAULTS["stereo"]
    for name, sign in (("stereo_left", -1.0), ("stereo_right", 1.0)):
        c = cams[name]
        p = c.pos if c.pos is not None else None
        R = look_at(centre, target)
        if p is None:
            p = centre + sign * STEREO_BASELINE_M / 2 * R[:, 0]
        else:
            R = look_at(p, c.target if c.target is not None else p + (target - centre))
        _add(world, name, p, R, c.fovy)
    # wrist cameras, in each palm body; the left one is the mirror of the right one
    for side, palm in palms.items():
        name = f"{side}_wrist"
        pos, target = pose(name, "wrist")
        up = np.array([0.0, -1.0, 0.0])        # back of the hand is "up" in the image
        if side == "left":
            pos, target = mirror_vec(pos), mirror_vec(target)
        _add(palm, name, pos, look_at(pos, target, up=up), cams[name].fovy)
    return list(emb.cameras)
