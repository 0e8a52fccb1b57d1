"""Cached robot scenes for the embodiment tests (one compile per embodiment and variant)."""

from __future__ import annotations

import functools

import mujoco
import numpy as np

import sim.physics as physics
from sim.embodiment import add_bimanual_robot
from sim.embodiment.description import load_embodiment
from sim.embodiment.mirror import mirror_vec
from sim.scene.objects import add_free_object

TABLE_TOP_Z = 0.75


@functools.lru_cache(maxsize=None)
def robot_scene(name: str, with_probes: bool = False):
    """Floor + robot (no table: the IK poses may pass where a table would be); optionally one free
    grasp-probe cylinder per hand, placed in the open hand at home."""
    spec = mujoco.MjSpec()
    physics.configure_options(spec)
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[3, 3, 0.1])
    spec.worldbody.add_light(name="sun", pos=[0, 0, 3], dir=[0, 0, -1], castshadow=False)
    layout = add_bimanual_robot(spec, name)
    if with_probes:
        emb = load_embodiment(name)
        probe = emb.hand.grasp_probe
        model0 = spec.compile()
        data0 = mujoco.MjData(model0)
        layout.apply_home(model0, data0)
        for side, sl in layout.sides.items():
            bid = model0.body(sl.hand_base).id
            R, p = data0.xmat[bid].reshape(3, 3), data0.xpos[bid]
            pos_h = probe.pos if side == "right" else mirror_vec(probe.pos)
            axis_h = probe.axis if side == "right" else mirror_vec(probe.axis)
            pos_w = p + R @ pos_h
            # built like a task object (same contact stiffness), the cylinder axis along axis_h
            quat = np.zeros(4)
            mujoco.mju_quatZ2Vec(quat, R @ axis_h)
            add_free_object(spec, f"{side}_probe", "cylinder", [probe.radius, probe.half_length], probe.mass,
                            1.0, [0.9, 0.5, 0.1, 1], pos_w, quat)
    model = spec.compile()
    return model, layout


def fresh_data(model, layout) -> mujoco.MjData:
    data = mujoco.MjData(model)
    layout.apply_home(model, data)
    return data


