"""Tiny MjSpec scenes with analytic labels (a uniquely named helper module, unlike conftest).

The camera looks along +y from (0, -0.6, 0.05), level with the centre of a 10 cm cube standing on
the floor at the origin, so the cube's silhouette is exactly its front face (y = -0.05).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from sim.labels.ids import LabelIds  # noqa: E402

WIDTH, HEIGHT = 64, 48
FOVY = 45.0
CAMERA_POS = np.array([0.0, -0.6, 0.05])
CUBE_HALF = 0.05


def new_spec() -> mujoco.MjSpec:
    spec = mujoco.MjSpec()
    spec.visual.global_.offwidth = WIDTH
    spec.visual.global_.offheight = HEIGHT
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[2, 2, 0.1])
    # camera x = world x, camera up = world z: it looks along +y
    spec.worldbody.add_camera(name="cam", pos=CAMERA_POS.tolist(), xyaxes=[1, 0, 0, 0, 0, 1], fovy=FOVY)
    return spec


def add_free_body(spec, name, pos, geoms, quat=(1, 0, 0, 0)):
    """A free body carrying `geoms`: dicts of MjsGeom attributes (type, size, pos, quat, ...)."""
    body = spec.worldbody.add_body(name=name, pos=list(pos), quat=list(quat))
    body.add_freejoint(name=f"{name}_free")
    for k, g in enumerate(geoms):
        body.add_geom(name=f"{name}/{k}", **g)
    return body


def box(half, pos=(0, 0, 0), rgba=(0.8, 0.2, 0.2, 1)):
    return {"type": mujoco.mjtGeom.mjGEOM_BOX, "size": list(half), "pos": list(pos), "rgba": list(rgba)}


def cube_scene(occluder: bool = False) -> tuple[mujoco.MjModel, mujoco.MjData, LabelIds]:
    """The cube "target" on the floor; with `occluder`, a second free cube "occluder" parked out of
    sight at x = 3 (move it with `place`)."""
    spec = new_spec()
    add_free_body(spec, "target", (0, 0, CUBE_HALF), [box([CUBE_HALF] * 3)])
    objects = [("target", "cube")]
    if occluder:
        add_free_body(spec, "occluder", (3, 0, CUBE_HALF), [box([0.03, 0.01, 0.1], rgba=(0.2, 0.2, 0.8, 1))])
        objects.append(("occluder", "blocker"))
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data, LabelIds.build(model, objects, {})


def place(model, data, name, pos, quat=(1, 0, 0, 0)) -> None:
    adr = model.jnt_qposadr[model.joint(f"{name}_free").id]
    data.qpos[adr:adr + 7] = [*pos, *quat]
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)


def render_seg(model, data, camera="cam") -> np.ndarray:
    from sim.labels.segmentation import render_segmentation

    with mujoco.Renderer(model, height=HEIGHT, width=WIDTH) as renderer:
        renderer.update_scene(data, camera=camera)
        return render_segmentation(renderer)


def project(points: np.ndarray) -> np.ndarray:
    """Pixel-edge image coordinates (u, v) of world points for the scene camera (looking along +y)."""
    f = (HEIGHT / 2) / np.tan(np.deg2rad(FOVY) / 2)
    rel = np.asarray(points, float) - CAMERA_POS
    depth = rel[:, 1]
    return np.stack([f * rel[:, 0] / depth + WIDTH / 2, f * -rel[:, 2] / depth + HEIGHT / 2], axis=1)


def corners(centre, half) -> np.ndarray:
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    return np.asarray(centre, float) + signs * np.asarray(half, float)
