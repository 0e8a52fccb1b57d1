"""Every embodiment in sim/catalog/embodiments: build, rest, limits, grasp, IK, FK, cameras, mirror."""

from __future__ import annotations

import math
import os

import mujoco
import numpy as np
import pytest

import sim.physics as physics
from sim.embodiment import embodiment_names, load_embodiment
from sim.embodiment.description import CAMERA_NAMES, mat_to_quat, quat_to_mat
from sim.embodiment.mirror import M, side_transform

from embodiment_scenes import fresh_data, robot_scene

SIDES = ("left", "right")


def site_pose(model, data, name):
    sid = model.site(name).id
    return data.site_xpos[sid].copy(), data.site_xmat[sid].reshape(3, 3).copy()


def rot_err(Ra, Rb) -> float:
    c = (np.trace(Ra.T @ Rb) - 1) / 2
    return float(math.acos(np.clip(c, -1, 1)))


def test_unknown_embodiment_lists_valid_names():
    with pytest.raises(ValueError, match="ur5_rh5dg2"):
        load_embodiment("no_such_robot")


def test_compiles_and_layout(embodiment, scene):
    model, layout = scene
    emb = load_embodiment(embodiment)
    assert model.nu == len(layout.actuator_names) == layout.home_ctrl.shape[0]
    adr = [model.joint(n).qposadr[0] for n in layout.joint_names]
    assert adr == sorted(adr), "joint_names must be in qpos order"
    assert [model.actuator(i).name for i in range(model.nu)] == layout.actuator_names
    nfing = len(emb.hand.fingers)
    for side, sl in layout.sides.items():
        assert len(sl.arm_joints) == emb.arm.dof
        assert len(sl.tactile_sites) == nfing and set(sl.tactile_bodies) == set(sl.tactile_sites)
        for s in sl.tactile_sites:
            assert model.site(s).bodyid[0] == model.body(sl.tactile_bodies[s]).id
        assert model.body(sl.hand_base).id >= 0 and sl.hand_base in sl.hand_bodies
    assert sum(len(sl.tactile_sites) for sl in layout.sides.values()) in (8, 10)
    for cam in CAMERA_NAMES:
        assert model.camera(cam).id >= 0


def test_rest_at_home(embodiment, scene):
    """1,000 control steps holding home_ctrl: no blow-up, wrist sites move < 1 mm, no self-contact."""
    model, layout = scene
    data = fresh_data(model, layout)
    robot_geoms = set()
    for i in range(model.ngeom):
        if model.body(model.geom_bodyid[i]).name not in ("world",):
            robot_geoms.add(i)
    contacts = [(model.body(model.geom_bodyid[c.geom1]).name, model.body(model.geom_bodyid[c.geom2]).name)
                for c in data.contact[: data.ncon]]
    assert not [c for c in contacts if "world" not in c], f"self-contacts at home: {contacts}"
    w0 = {s: site_pose(model, data, layout.sides[s].wrist_site)[0] for s in SIDES}
    for _ in range(1000):
        physics.step_control(model, data, layout.home_ctrl)
    assert np.all(np.isfinite(data.qpos))
    for s in SIDES:
        drift = np.linalg.norm(site_pose(model, data, layout.sides[s].wrist_site)[0] - w0[s])
        assert drift < 1e-3, f"{s} wrist drifted {drift * 1e3:.2f} mm"


def test_home_is_palm_down_in_front_above_table(embodiment, scene):
    model, layout = scene
    data = fresh_data(model, layout)
    for s in SIDES:
        p, R = site_pose(model, data, layout.sides[s].wrist_site)
        assert R[:, 1] @ np.array([0, 0, -1.0]) > 0.9, "palm normal (+y) must face down"
        assert p[2] > 0.85 and -0.45 < p[1] < 0.2 and abs(p[0]) < 0.5


def test_joint_limits_respected(embodiment, scene):
    model, layout = scene
    data = fresh_data(model, layout)
    ids = layout.actuator_ids(model)
    ctrl = layout.home_ctrl.copy()
    hand = [layout.actuator_names.index(a) for s in SIDES for a in layout.sides[s].hand_actuators]
    elbow = [layout.actuator_names.index(layout.sides[s].arm_actuators[2]) for s in SIDES]
    for bound in (1, 0):
        for i in hand:
            r = model.actuator_ctrlrange[ids[i]]
            ctrl[i] = r[bound] + (1.0 if bound else -1.0)
        for i in elbow:
            r = model.actuator_ctrlrange[ids[i]]
            ctrl[i] = layout.home_ctrl[i] + (2.0 if layout.home_ctrl[i] > 0 else -2.0) if bound else layout.home_ctrl[i]
        for _ in range(90):
            physics.step_control(model, data, ctrl)
            q = data.qpos
            for j in range(model.njnt):
                if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE and model.jnt_limited[j]:
                    lo, hi = model.jnt_range[j]
                    v = q[model.jnt_qposadr[j]]
                    assert lo - 0.03 <= v <= hi + 0.03, f"{model.joint(j).name}={v:.3f} outside [{lo}, {hi}]"
    assert np.all(np.isfinite(data.qpos))


# Known open issue: in these hands (three flexion links with a coupled distal joint) the proximal
# phalanges flick the probe out of the hand while closing; the grasp_probe placement / closing
# sequence still needs tuning. strict: the test reports when they start passing.
GRASP_KNOWN_FAILING = {"jaka_zu7_dexhand021", "panda_orca", "ur5_shadow"}


def test_hands_hold_cylinder(embodiment, request):
    """A free cylinder placed in each open hand (gravity off), the fingers close, gravity on: held 1 s."""
    if embodiment in GRASP_KNOWN_FAILING:
        request.applymarker(pytest.mark.xfail(strict=True, reason="probe ejected while closing (open issue)"))
    model, layout = robot_scene(embodiment, with_probes=True)
    emb = load_embodiment(embodiment)
    probe = emb.hand.grasp_probe
    assert probe is not None, f"{emb.hand.path} has no grasp_probe"
    data = fresh_data(model, layout)
    g = model.opt.gravity.copy()
    ctrl = layout.home_ctrl.copy()
    for s in SIDES:
        for a, v in probe.close.items():
            ctrl[layout.actuator_names.index(f"{s}_{a}")] = v
    try:
        model.opt.gravity[:] = 0
        for _ in range(60):
            physics.step_control(model, data, ctrl)
        start = {s: data.body(f"{s}_probe").xpos.copy() for s in SIDES}
        palm0 = {s: data.body(layout.sides[s].hand_base).xpos.copy() for s in SIDES}
        model.opt.gravity[:] = g
        for _ in range(60):
            physics.step_control(model, data, ctrl)
    finally:
        model.opt.gravity[:] = g
    for s in SIDES:
        rel0 = start[s] - palm0[s]
        rel1 = data.body(f"{s}_probe").xpos - data.body(layout.sides[s].hand_base).xpos
        slip = np.linalg.norm(rel1 - rel0)
        hand_ids = {model.body(b).id for b in layout.sides[s].hand_bodies}
        pid = model.body(f"{s}_probe").id
        touching = sum(1 for c in data.contact[: data.ncon]
                       if {model.geom_bodyid[c.geom1], model.geom_bodyid[c.geom2]} & hand_ids
                       and pid in (model.geom_bodyid[c.geom1], model.geom_bodyid[c.geom2]))
        assert touching >= 2, f"{s} hand does not hold the cylinder ({touching} contacts)"
        assert slip < 0.02, f"{s} cylinder slipped {slip * 1e3:.1f} mm in 1 s"


# the short RM65 (0.61 m reach) covers a smaller part of the workspace around its home pose
REACH_SCALE = {"rm65": 0.55}


def _targets(layout, model, data):
    """Five reachable wrist poses per side: palm-down over the workspace, some tilted."""
    scale = REACH_SCALE.get(load_embodiment(layout.embodiment).arm.name, 1.0)
    base = []
    for dx, dy, dz, tilt in ((0.0, 0.15, -0.12, 0.0), (-0.12, 0.3, -0.15, 0.0), (0.06, 0.05, -0.05, 0.3),
                             (-0.05, 0.25, -0.08, -0.25), (0.08, 0.35, -0.1, 0.0)):
        base.append((np.array([dx, dy, dz]), tilt))
    out = {}
    for s in SIDES:
        p0, R0 = site_pose(model, data, layout.sides[s].wrist_site)
        sign = 1.0 if s == "right" else -1.0
        ts = []
        for d, tilt in base:
            Rt = R0 @ quat_to_mat([math.cos(tilt / 2), 0, 0, math.sin(tilt / 2)])   # yaw about the fingers
            ts.append((p0 + scale * np.array([sign * d[0], d[1], d[2]]), Rt))
        out[s] = ts
    return out


def test_ik_reaches_and_mujoco_tracks(embodiment, scene):
    model, layout = scene
    data = fresh_data(model, layout)
    targets = _targets(layout, model, data)
    for s in SIDES:
        kin = layout.arm_kinematics(s)
        sl = layout.sides[s]
        q_home = np.array([data.qpos[model.joint(n).qposadr[0]] for n in sl.arm_joints])
        idx = [layout.actuator_names.index(a) for a in sl.arm_actuators]
        for k, (p, R) in enumerate(targets[s]):
            r = kin.ik(p, mat_to_quat(R), q_home)
            assert r.success, f"{s} target {k}: IK err {r.pos_err_m * 1e3:.2f} mm {math.degrees(r.rot_err_rad):.2f} deg"
            d = fresh_data(model, layout)
            ctrl = layout.home_ctrl.copy()
            ctrl[idx] = r.q
            for _ in range(120):
                physics.step_control(model, d, ctrl)
            ps, Rs = site_pose(model, d, sl.wrist_site)
            assert np.linalg.norm(ps - p) < 2e-3, f"{s} target {k}: MuJoCo site off by {np.linalg.norm(ps - p) * 1e3:.2f} mm"
            assert rot_err(Rs, R) < math.radians(2)


def test_pinocchio_fk_matches_mujoco(embodiment, scene):
    model, layout = scene
    data = mujoco.MjData(model)
    rng = np.random.default_rng(0)
    for _ in range(5):
        layout.apply_home(model, data)
        for s in SIDES:
            kin = layout.arm_kinematics(s)
            q = rng.uniform(np.maximum(kin.lower, -3), np.minimum(kin.upper, 3))
            for n, v in zip(layout.sides[s].arm_joints, q):
                data.qpos[model.joint(n).qposadr[0]] = v
            mujoco.mj_kinematics(model, data)
            p, R = site_pose(model, data, layout.sides[s].wrist_site)
            pf, qf = kin.fk(q)
            assert np.linalg.norm(p - pf) < 1e-6
            assert rot_err(R, quat_to_mat(qf)) < 1e-6


def test_left_hand_mirrors_right(embodiment, scene):
    """Same hand joint angles -> left hand link poses (in the hand base frame) are the mirror image."""
    model, layout = scene
    data = fresh_data(model, layout)
    rng = np.random.default_rng(1)
    L, Rt = layout.sides["left"], layout.sides["right"]
    for jl, jr in zip(L.hand_joints, Rt.hand_joints):
        lo, hi = model.jnt_range[model.joint(jr).id]
        v = rng.uniform(lo, hi)
        data.qpos[model.joint(jl).qposadr[0]] = v
        data.qpos[model.joint(jr).qposadr[0]] = v
    mujoco.mj_kinematics(model, data)

    def rel(side_layout, body):
        b0 = model.body(side_layout.hand_base).id
        b = model.body(body).id
        R0 = data.xmat[b0].reshape(3, 3)
        return R0.T @ (data.xpos[b] - data.xpos[b0]), R0.T @ data.xmat[b].reshape(3, 3)

    for bl, br in zip(L.hand_bodies, Rt.hand_bodies):
        pl, Rl = rel(L, bl)
        pr, Rr = rel(Rt, br)
        np.testing.assert_allclose(pl, M @ pr, atol=1e-9)
        np.testing.assert_allclose(Rl, M @ Rr @ M, atol=1e-9)
    # tactile sites are mirrored too
    for sl_, sr_ in zip(L.tactile_sites, Rt.tactile_sites):
        assert model.site(sl_).bodyid[0] == model.body(L.tactile_bodies[sl_]).id
        np.testing.assert_allclose(model.site_pos[model.site(sl_).id], M @ model.site_pos[model.site(sr_).id], atol=1e-12)


@pytest.mark.skipif(os.environ.get("MUJOCO_GL") not in ("egl", "osmesa"), reason="needs MUJOCO_GL=egl|osmesa")
def test_cameras_render(embodiment, scene):
    model, layout = scene
    data = fresh_data(model, layout)
    with mujoco.Renderer(model, 48, 64) as renderer:
        for cam in CAMERA_NAMES:
            renderer.update_scene(data, camera=cam)
            img = renderer.render()
            assert img.shape == (48, 64, 3)
            assert img.std() > 1.0, f"camera {cam} renders a constant image"
