"""Every embodiment in sim/catalog/embodiments: build, rest, limits, servo speed, couplings, grasp, reach, IK, FK,
cameras (render, calibration), mirror."""

from __future__ import annotations

import math
import os

import mujoco
import numpy as np
import pytest

import sim.physics as physics
from sim.embodiment import ArmKinematics, description, embodiment_names, load_embodiment
from sim.embodiment.builder import home_arm_angles
from sim.embodiment.description import CAMERA_NAMES, THUMB, mat_to_quat, quat_to_mat
from sim.embodiment.mirror import M
from sim.embodiment.reach import reach_along
from sim.render import MJ_TO_CV, intrinsic_matrix

from catalog_files import edited_catalog_file
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


def test_arm_without_reach_names_file_and_field(tmp_path, monkeypatch):
    with edited_catalog_file(monkeypatch, tmp_path, "arms", "rm65", lambda raw: raw.pop("reach")):
        with pytest.raises(ValueError, match=r"rm65.yaml: field 'reach': .*missing"):
            description.load_arm("rm65")


@pytest.mark.parametrize("bad, words", [(["elbow"], "not a joint"), ("elbow_joint", "a list of joint names")])
def test_a_bad_ik_keep_sign_names_file_and_field(tmp_path, monkeypatch, bad, words):
    with edited_catalog_file(monkeypatch, tmp_path, "arms", "ur5", lambda raw: raw.update(ik_keep_sign=bad)):
        with pytest.raises(ValueError, match=rf"ur5.yaml: field 'ik_keep_sign.*{words}"):
            description.load_arm("ur5")


def test_ur5_ik_keeps_the_elbow_on_its_home_side():
    """A UR5 stretched straight out (a lid pushed open, a bin reached over) is solved on the home seed's
    elbow branch: the IK stops the elbow 0.05 rad short of straight, on that side, for both arms (it
    would straighten to 0.07 rad, from where a flip is one step away); the joint limits stay as they are."""
    emb = load_embodiment("ur5_rh56dfx")
    elbow = [j.name for j in emb.arm.joints].index("elbow_joint")
    for side in SIDES:
        kin = ArmKinematics(emb.arm, emb.mounts[side], emb.hand, side)
        home = emb.arm.home_seed[side]
        pos, quat = kin.fk(home)
        far = kin.ik(pos + np.array([0.0, 0.6, 0.0]), quat, home).q     # beyond reach: stretched straight
        assert far[elbow] == pytest.approx(np.sign(home[elbow]) * description.KEEP_SIGN_MARGIN_RAD)
        assert (kin.lower[elbow], kin.upper[elbow]) == pytest.approx((-np.pi, np.pi), abs=1e-3)


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


def test_coupled_joints_follow_their_master(embodiment, scene):
    """Mimic joints are joint equalities: with the hand driven to mid-range, every coupled joint sits
    where its coupling polynomial of the master puts it. The thumb and the fingers are driven in turn
    (the other kept open): together at mid-range a thumb that can pinch presses on the fingertips."""
    model, layout = scene
    hand = load_embodiment(embodiment).hand
    assert model.neq == 2 * len(hand.couplings)
    thumb_joints = {j.name for link in hand.links if link.finger == THUMB for j in link.joints}
    for thumb_turn in (True, False):
        data = fresh_data(model, layout)
        ctrl = layout.home_ctrl.copy()
        for s in SIDES:
            for a in hand.actuators:
                if (a.joint in thumb_joints) == thumb_turn:
                    lo, hi = model.actuator_ctrlrange[model.actuator(f"{s}_{a.name}").id]
                    ctrl[layout.actuator_names.index(f"{s}_{a.name}")] = (lo + hi) / 2
        for _ in range(60):
            physics.step_control(model, data, ctrl)
        for s in SIDES:
            for c in hand.couplings:
                master = data.qpos[model.joint(f"{s}_{c.master}").qposadr[0]]
                follower = data.qpos[model.joint(f"{s}_{c.joint}").qposadr[0]]
                expected = np.clip(sum(k * master ** i for i, k in enumerate(c.polycoef)),
                                   *hand.joint(c.joint).range)
                assert abs(follower - expected) < 0.01, f"{s}_{c.joint} = {follower:.3f}, coupling gives {expected:.3f}"


def _peak_speeds(model, data, ctrl, dofs, seconds: float) -> np.ndarray:
    """Hold ``ctrl`` for ``seconds``; the largest |qvel| of each dof over every physics step."""
    dofs = np.asarray(dofs)
    peak = np.zeros(len(dofs))
    data.ctrl[:] = ctrl
    for _ in range(math.ceil(seconds / model.opt.timestep)):
        mujoco.mj_step(model, data)
        peak = np.maximum(peak, np.abs(data.qvel[dofs]))
    return peak


def _assert_within_speed(model, peak, dofs, v_max) -> None:
    ratio = np.asarray(peak) / np.asarray(v_max)
    k = int(np.argmax(ratio))
    assert ratio[k] <= 1.05, (f"{model.joint(model.dof_jntid[dofs[k]]).name} reached {peak[k]:.2f} rad/s, "
                              f"real max {v_max[k]:.2f}")


def test_step_tracked_within_real_speed(embodiment, scene):
    """Step commands move each joint no faster than its real maximum speed: first every hand
    actuator to the far end of its range, then the right elbow 0.6 rad towards the middle of its
    range (clear of the other arm), which gets there in about the time the real joint needs."""
    model, layout = scene
    emb = load_embodiment(embodiment)
    data = fresh_data(model, layout)
    ctrl = layout.home_ctrl.copy()
    dofs, v_max, seconds = [], [], 0.0
    for s in SIDES:
        for a in emb.hand.actuators:
            i = layout.actuator_names.index(f"{s}_{a.name}")
            lo, hi = model.actuator_ctrlrange[model.actuator(f"{s}_{a.name}").id]
            far = hi if ctrl[i] - lo < hi - ctrl[i] else lo
            seconds = max(seconds, abs(far - ctrl[i]) / a.velocity)
            ctrl[i] = far
            dofs.append(model.joint(f"{s}_{a.joint}").dofadr[0])
            v_max.append(a.velocity)
    _assert_within_speed(model, _peak_speeds(model, data, ctrl, dofs, seconds + 0.3), dofs, v_max)
    elbow = emb.arm.joints[2]
    i_elbow = layout.actuator_names.index(layout.sides["right"].arm_actuators[2])
    elbow_q = model.joint(layout.sides["right"].arm_joints[2])
    ctrl[i_elbow] += 0.6 * np.sign(sum(elbow.range) / 2 - ctrl[i_elbow])
    peak = _peak_speeds(model, data, ctrl, [elbow_q.dofadr[0]], 0.6 / elbow.velocity + 0.5)
    _assert_within_speed(model, peak, [elbow_q.dofadr[0]], [elbow.velocity])
    assert abs(data.qpos[elbow_q.qposadr[0]] - ctrl[i_elbow]) < 0.01, "the right elbow did not reach its step target"


# Probe placements in the hand frame (metres, right hand; mirrored on the left, so each sideways
# shift is tried both ways): the hand file's, and shifted along the fingers and the cylinder axis.
PROBE_SHIFTS = ((0.0, 0.0, 0.0), (0.005, 0.0, -0.004), (-0.005, 0.0, 0.004))
CLOSING_MOVE_MAX_M = 0.04   # a cylinder flicked further while the fingers close was not closed on


def _finger_of(emb, side: str) -> dict[str, str]:
    return {f"{side}_{lk.name}": lk.finger for lk in emb.hand.links if lk.finger}


@pytest.mark.parametrize("shift", PROBE_SHIFTS, ids=("declared", "wristward", "fingerward"))
def test_hands_hold_cylinder(embodiment, shift):
    """A free cylinder placed in each open hand (gravity off), the fingers close on it without
    pushing it out, gravity on: at least two fingers hold it for 1 s."""
    model, layout = robot_scene(embodiment, with_probes=True)
    emb = load_embodiment(embodiment)
    probe = emb.hand.grasp_probe
    assert probe is not None, f"{emb.hand.path} has no grasp_probe"
    data = fresh_data(model, layout)
    for s in SIDES:
        palm = data.body(layout.sides[s].hand_base)
        d = np.asarray(shift) if s == "right" else M @ np.asarray(shift)
        adr = model.joint(f"{s}_probe_free").qposadr[0]
        data.qpos[adr:adr + 3] += palm.xmat.reshape(3, 3) @ d
    mujoco.mj_forward(model, data)
    g = model.opt.gravity.copy()
    ctrl = layout.home_ctrl.copy()
    for s in SIDES:
        for a, v in probe.close.items():
            ctrl[layout.actuator_names.index(f"{s}_{a}")] = v

    def in_palm(s):
        palm = data.body(layout.sides[s].hand_base)
        return palm.xmat.reshape(3, 3).T @ (data.body(f"{s}_probe").xpos - palm.xpos)

    placed = {s: in_palm(s) for s in SIDES}
    try:
        model.opt.gravity[:] = 0
        for _ in range(60):
            physics.step_control(model, data, ctrl)
        closed = {s: in_palm(s) for s in SIDES}
        model.opt.gravity[:] = g
        for _ in range(60):
            physics.step_control(model, data, ctrl)
    finally:
        model.opt.gravity[:] = g
    for s in SIDES:
        moved = np.linalg.norm(closed[s] - placed[s])
        assert moved < CLOSING_MOVE_MAX_M, f"{s} hand pushed the cylinder {moved * 1e3:.0f} mm while closing"
        slip = np.linalg.norm(in_palm(s) - closed[s])
        finger_of = _finger_of(emb, s)
        pid = model.body(f"{s}_probe").id
        fingers = set()
        for c in data.contact[: data.ncon]:
            b1, b2 = model.geom_bodyid[c.geom1], model.geom_bodyid[c.geom2]
            if pid in (b1, b2):
                fingers.add(finger_of.get(model.body(b2 if b1 == pid else b1).name))
        fingers.discard(None)
        assert len(fingers) >= 2, f"{s} hand does not hold the cylinder (fingers touching: {sorted(fingers)})"
        assert slip < 0.02, f"{s} cylinder slipped {slip * 1e3:.1f} mm in 1 s"


# wrist offsets from home (right side; x mirrored on the left) and yaw about the fingers
TARGET_OFFSETS = (((0.0, 0.15, -0.12), 0.0), ((-0.12, 0.3, -0.15), 0.0), ((0.06, 0.05, -0.05), 0.3),
                  ((-0.05, 0.25, -0.08), -0.25), ((0.08, 0.35, -0.1), 0.0))


def _targets(layout, model, data):
    """Five reachable wrist poses per side: palm-down over the workspace, some yawed, each offset
    shortened to the arm's declared reach from home (`reach.home_radius_m` of the arm file)."""
    reach = load_embodiment(layout.embodiment).arm.reach_m
    out = {}
    for s in SIDES:
        p0, R0 = site_pose(model, data, layout.sides[s].wrist_site)
        sign = 1.0 if s == "right" else -1.0
        ts = []
        for d, tilt in TARGET_OFFSETS:
            d = np.array([sign * d[0], d[1], d[2]])
            d *= min(1.0, reach / np.linalg.norm(d))
            Rt = R0 @ quat_to_mat([math.cos(tilt / 2), 0, 0, math.sin(tilt / 2)])   # yaw about the fingers
            ts.append((p0 + d, Rt))
        out[s] = ts
    return out


def _first_embodiment_per_arm() -> dict[str, str]:
    out = {}
    for name in embodiment_names():
        out.setdefault(load_embodiment(name).arm.name, name)
    return out


@pytest.mark.parametrize("arm,embodiment_name", sorted(_first_embodiment_per_arm().items()))
def test_declared_reach_is_within_the_measured_reach(arm, embodiment_name):
    """The arm file's reach holds straight ahead and ahead-and-down of home (the full measurement,
    every direction over the table, is `python -m sim.embodiment.reach`)."""
    emb = load_embodiment(embodiment_name)
    kin = ArmKinematics(emb.arm, emb.mounts["right"], emb.hand, "right")
    q_home = np.array(home_arm_angles(embodiment_name)[1])
    p0, q0 = kin.fk(q_home)
    for d in ((0.0, 1.0, 0.0), (0.0, 0.7071, -0.7071)):
        r = reach_along(kin, q_home, p0, quat_to_mat(q0), np.array(d), 0.01)
        assert r >= emb.arm.reach_m, f"{arm}: reaches {r:.2f} m towards {d}, file declares {emb.arm.reach_m}"


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


@pytest.mark.skipif(os.environ.get("MUJOCO_GL") not in ("egl", "osmesa"), reason="needs MUJOCO_GL=egl|osmesa")
def test_camera_intrinsics_match_the_render(embodiment, scene):
    """The stored pinhole intrinsics (sim.render.intrinsic_matrix) and extrinsics are the cameras'
    calibration: a ray cast (mj_ray) through a pixel's centre with them hits the geom the camera
    renders there, at the depth it renders."""
    model, layout = scene
    data = fresh_data(model, layout)
    width, height = 64, 48
    hit = np.array([-1], dtype=np.int32)
    with mujoco.Renderer(model, height, width) as renderer:
        for cam in CAMERA_NAMES:
            cid = model.camera(cam).id
            renderer.enable_depth_rendering()
            renderer.update_scene(data, camera=cam)
            depth = renderer.render().copy()
            renderer.disable_depth_rendering()
            renderer.enable_segmentation_rendering()
            renderer.update_scene(data, camera=cam)
            seg = renderer.render().copy()
            renderer.disable_segmentation_rendering()
            K_inv = np.linalg.inv(intrinsic_matrix(float(model.cam_fovy[cid]), width, height))
            world_from_cam = data.cam_xmat[cid].reshape(3, 3) @ MJ_TO_CV
            rays = agree = 0
            errors = []
            for v in range(1, height, 4):
                for u in range(1, width, 4):
                    d = world_from_cam @ (K_inv @ np.array([u + 0.5, v + 0.5, 1.0]))   # unit optical depth
                    t = mujoco.mj_ray(model, data, data.cam_xpos[cid], d / np.linalg.norm(d), None, 1, -1, hit)
                    if t < 0:
                        continue
                    rays += 1
                    if seg[v, u, 0] == hit[0]:
                        agree += 1
                        z = t / np.linalg.norm(d)
                        errors.append(abs(z - depth[v, u]) / z)
            assert rays > 50 and agree > 0.85 * rays, f"{cam}: {agree} of {rays} rays hit the rendered geom"
            assert np.median(errors) < 1e-3, f"{cam}: rays and render disagree on depth by {np.median(errors):.2%}"
