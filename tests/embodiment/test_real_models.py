"""The optional real-model path: a hand file's ``real_model:`` block (MuJoCo Menagerie Shadow, Allegro)
built in place of the generated hand, with the same names.

Tests that need the models skip when neither ``$MENAGERIE_ROOT`` nor ``../shared/models/menagerie``
(next to the repository) holds them; the error paths run everywhere.
"""

import dataclasses
import functools
import os
from pathlib import Path

import mujoco
import numpy as np
import pytest

import sim.physics as physics
from sim.embodiment import add_bimanual_robot, embodiment_names
from sim.embodiment.description import load_embodiment
from sim.embodiment.mirror import M
from sim.embodiment.real_model import load_model_spec
from sim.embodiment.real_model_file import HAND_MODEL_ENV, MENAGERIE_ENV, RealModelError
from tactile.rig import TactileRig

from catalog_files import edited_catalog_file

SHARED_MENAGERIE = Path(__file__).resolve().parents[3] / "shared" / "models" / "menagerie"
REST_STEPS = 1000
REST_DRIFT_M = 1e-3
# fidelity tolerances, generated vs real at home (q = 0 clipped to the limits), hand base frame, for
# every finger incl. the thumb (the generated thumbs follow the real joint chains): finger length
# (finger root -> pad centre), pad centre position, and tip reach (root -> farthest collision point
# along the distal link). Measured: Allegro lengths within 0.4 mm, reach 0.0, pads 3.7 mm apart (the
# real_model link_frame lifts the pads 3.7 mm off the real caps); Shadow lengths 0.0, thumb reach 0.0,
# finger reach +3.0 mm (capsule tips vs the real distal meshes), pads within 1.5 mm.
LENGTH_TOL_M = 0.002
FINGERTIP_TOL_M = 0.004
REACH_TOL_M = 0.0035

REAL = [e for e in embodiment_names() if load_embodiment(e).hand.real_model is not None]


def _menagerie_root() -> str | None:
    env = os.environ.get(MENAGERIE_ENV)
    if env and Path(env).is_dir():
        return env
    return str(SHARED_MENAGERIE) if SHARED_MENAGERIE.is_dir() else None


needs_models = pytest.mark.skipif(_menagerie_root() is None,
                                  reason="real hand models absent (no MENAGERIE_ROOT, no ../shared/models/menagerie)")


@functools.lru_cache(maxsize=None)
def _robot(name: str, hand_model: str):
    old = os.environ.get(MENAGERIE_ENV)
    os.environ[MENAGERIE_ENV] = _menagerie_root()
    try:
        spec = mujoco.MjSpec()
        physics.configure_options(spec)
        spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[3, 3, 0.1])
        layout = add_bimanual_robot(spec, name, hand_model=hand_model)
        slab = spec.worldbody.add_body(name="slab", pos=[0, 0, -1])
        slab.add_freejoint(name="slab_free")
        slab.add_geom(name="slab", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.02, 0.02, 0.004])
        model = spec.compile()
    finally:
        if old is None:
            os.environ.pop(MENAGERIE_ENV, None)
        else:
            os.environ[MENAGERIE_ENV] = old
    return model, layout


def _home(name: str, hand_model: str):
    model, layout = _robot(name, hand_model)
    data = mujoco.MjData(model)
    layout.apply_home(model, data)
    return model, data, layout


def _in_hand_frame(model, data, layout, side: str, point) -> np.ndarray:
    b = model.body(layout.sides[side].hand_base).id
    return data.xmat[b].reshape(3, 3).T @ (np.asarray(point) - data.xpos[b])


def test_the_real_hands_are_found_in_the_catalog():
    assert {load_embodiment(e).hand.name for e in REAL} == {"shadow", "allegro"}


@needs_models
@pytest.mark.parametrize("name", REAL)
def test_real_model_compiles_with_the_generated_joint_and_actuator_names(name):
    model, layout = _robot(name, "real")
    gen_model, gen_layout = _robot(name, "generated")
    assert model.nmesh > 0 and gen_model.nmesh == 0
    assert (model.nq, model.nu) == (gen_model.nq, gen_model.nu)
    assert layout.actuator_names == gen_layout.actuator_names
    assert layout.joint_names == gen_layout.joint_names
    # ctrl is written as one array: the model's actuator order is the layout's
    assert [model.actuator(i).name for i in range(model.nu)] == layout.actuator_names
    # the home targets lie inside the real servos' ranges
    ids = layout.actuator_ids(model)
    lo, hi = model.actuator_ctrlrange[ids].T
    assert np.all(layout.home_ctrl >= lo - 1e-9) and np.all(layout.home_ctrl <= hi + 1e-9)


@needs_models
@pytest.mark.parametrize("name", REAL)
def test_real_hand_rests_at_home_without_drift(name):
    model, data, layout = _home(name, "real")
    sites = [s for sl in layout.sides.values() for s in (*sl.tactile_sites, sl.wrist_site)]
    ids = [model.site(s).id for s in sites]
    start = data.site_xpos[ids].copy()
    for _ in range(REST_STEPS):
        data.ctrl[:] = layout.home_ctrl
        mujoco.mj_step(model, data)
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))
    drift = np.linalg.norm(data.site_xpos[ids] - start, axis=1)
    assert drift.max() < REST_DRIFT_M, dict(zip(sites, drift.round(5)))


@needs_models
@pytest.mark.parametrize("name", REAL)
def test_tactile_and_wrist_sites_sit_on_the_mapped_model_bodies(name):
    model, data, layout = _home(name, "real")
    hand = load_embodiment(name).hand
    rm = hand.real_model
    sites = {s.name: s.attach_body for s in hand.tactile.sites}
    for side, sl in layout.sides.items():
        mp = rm.name_prefix[side]
        for site in sl.tactile_sites:
            link = sites[site[len(side) + 1:]]
            body = model.body(model.site(site).bodyid[0])
            assert body.name == f"{side}_{link}" == sl.tactile_bodies[site]
            parent = model.body(body.parentid[0]).name
            assert parent == f"{side}_{hand.name}_{mp}{rm.bodies[link]}"
        wrist = model.body(model.site(sl.wrist_site).bodyid[0])
        assert wrist.name == sl.hand_base == f"{side}_{hand.links[0].name}"
        assert model.body(wrist.parentid[0]).name == f"{side}_{hand.name}_{mp}{rm.root_body}"
    # Menagerie's own left model, placed so that it is the mirror of the right one: every pad and the
    # wrist site at M p in the hand base frame, pad normals mirrored too
    for site in layout.sides["right"].tactile_sites + ["right_wrist_site"]:
        r, left = model.site(site).id, model.site("left" + site[len("right"):]).id
        pr = _in_hand_frame(model, data, layout, "right", data.site_xpos[r])
        pl = _in_hand_frame(model, data, layout, "left", data.site_xpos[left])
        assert np.allclose(pl, M @ pr, atol=1e-6), site
        nr = data.site_xmat[r].reshape(3, 3)[:, 2]
        nl = data.site_xmat[left].reshape(3, 3)[:, 2]
        br = data.xmat[model.body(layout.sides["right"].hand_base).id].reshape(3, 3)
        bl = data.xmat[model.body(layout.sides["left"].hand_base).id].reshape(3, 3)
        assert np.allclose(bl.T @ nl, M @ (br.T @ nr), atol=1e-6), site


def _reach(model, data, bodies: set[int], origin, axis) -> float:
    """How far the bodies' collision geometry reaches from ``origin`` along ``axis`` (pads excluded)."""
    best = -np.inf
    for g in range(model.ngeom):
        if model.geom_bodyid[g] not in bodies or model.geom(g).name.endswith("_pad"):
            continue
        if model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0:     # visual only
            continue
        centre, rot, size = data.geom_xpos[g], data.geom_xmat[g].reshape(3, 3), model.geom_size[g]
        kind = model.geom_type[g]
        if kind == mujoco.mjtGeom.mjGEOM_MESH:
            mesh = model.geom_dataid[g]
            start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
            best = max(best, float(((model.mesh_vert[start:start + count] @ rot.T + centre - origin) @ axis).max()))
            continue
        local = rot.T @ axis
        if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
            extent = size[0]
        elif kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
            extent = abs(local[2]) * size[1] + size[0]
        elif kind == mujoco.mjtGeom.mjGEOM_CYLINDER:
            extent = abs(local[2]) * size[1] + size[0] * np.hypot(local[0], local[1])
        else:                                                                  # box (ellipsoid: its box)
            extent = float(np.abs(local * size).sum())
        best = max(best, float((centre - origin) @ axis + extent))
    return best


def _fidelity(name: str) -> dict[str, dict[str, float]]:
    """Per finger at home: root -> pad centre length, tip reach (root -> the farthest point of the
    fingertip's collision geometry along the distal link) for generated and real, and the pad gap."""
    hand = load_embodiment(name).hand
    out = {}
    runs = {hm: _home(name, hm) for hm in ("generated", "real")}
    for s in hand.tactile.sites:
        root = next(lk.name for lk in hand.links if lk.finger == s.finger)
        row = {}
        for hm, (model, data, layout) in runs.items():
            pad = data.site_xpos[model.site(f"right_{s.name}").id]
            root_id = model.body(f"right_{root}").id
            if hm == "real":      # the model's own body (our alias on it may be offset, see link_frame)
                root_id = model.body_parentid[root_id]
            origin = data.xpos[root_id]
            row[f"{hm}_length_mm"] = 1e3 * float(np.linalg.norm(pad - origin))
            row[f"{hm}_pad"] = _in_hand_frame(model, data, layout, "right", pad)
            link = model.body(f"right_{s.attach_body}").id
            tip = link if hm == "generated" else model.body_parentid[link]    # real: the model body
            bodies = {b for b in range(model.nbody) if b == tip or model.body_parentid[b] == tip}
            row[f"{hm}_reach_mm"] = 1e3 * _reach(model, data, bodies, origin, data.xmat[link].reshape(3, 3)[:, 2])
        row["pad_gap_mm"] = 1e3 * float(np.linalg.norm(row.pop("generated_pad") - row.pop("real_pad")))
        out[s.finger] = row
    return out


@needs_models
@pytest.mark.parametrize("name", REAL)
def test_generated_hand_matches_the_real_one_within_tolerance(name):
    figures = _fidelity(name)
    print(f"\n{name} at home, generated / real (mm): root->pad length, tip reach; pad centre gap")
    for finger, row in figures.items():
        print(f"  {finger:7s} length {row['generated_length_mm']:6.1f} / {row['real_length_mm']:6.1f}   "
              f"reach {row['generated_reach_mm']:6.1f} / {row['real_reach_mm']:6.1f}   gap {row['pad_gap_mm']:6.1f}")
    for finger, row in figures.items():
        assert abs(row["generated_length_mm"] - row["real_length_mm"]) < LENGTH_TOL_M * 1e3, (finger, row)
        assert abs(row["generated_reach_mm"] - row["real_reach_mm"]) < REACH_TOL_M * 1e3, (finger, row)
        assert row["pad_gap_mm"] < FINGERTIP_TOL_M * 1e3, (finger, row)


@needs_models
@pytest.mark.parametrize("name", REAL)
def test_tactile_rig_reads_a_plate_pressed_on_a_real_fingertip_pad(name):
    model, data, layout = _home(name, "real")
    rig = TactileRig(model, layout, ["slab"], 48, 1, 0.015)
    site = "right_index_tip"
    geom = model.geom(f"{site}_pad").id
    rot = data.geom_xmat[geom].reshape(3, 3)
    face = data.geom_xpos[geom] + rot[:, 2] * model.geom_size[geom][2]
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, rot.reshape(-1))
    adr = model.joint("slab_free").qposadr[0]
    data.qpos[adr:adr + 7] = [*(face + rot[:, 2] * (0.004 - 0.0005)), *quat]   # 0.5 mm into the pad
    mujoco.mj_forward(model, data)
    frame = rig.capture(data)
    touched = [n for n, m in zip(frame.site_names, frame.mask) if m.any()]
    # the 40 mm plate also reaches the neighbouring finger; never the other hand
    assert site in touched and not any(n.startswith("left_") for n in touched)
    assert frame.tacmap[frame.site_names.index(site)].max() > 0


def test_requesting_real_for_a_hand_without_a_block_names_the_hand_file():
    name = next(e for e in embodiment_names() if load_embodiment(e).hand.real_model is None)
    with pytest.raises(RealModelError, match=str(load_embodiment(name).hand.path)):
        add_bimanual_robot(mujoco.MjSpec(), name, hand_model="real")


def test_the_environment_variable_selects_the_hand_model(monkeypatch):
    name = next(e for e in embodiment_names() if load_embodiment(e).hand.real_model is None)
    monkeypatch.setenv(HAND_MODEL_ENV, "real")
    with pytest.raises(RealModelError, match="real_model"):
        add_bimanual_robot(mujoco.MjSpec(), name)
    monkeypatch.setenv(HAND_MODEL_ENV, "photoreal")
    with pytest.raises(RealModelError, match=HAND_MODEL_ENV):
        add_bimanual_robot(mujoco.MjSpec(), name)


def test_a_model_that_resolves_nowhere_names_the_file_and_what_was_searched(monkeypatch, tmp_path):
    hand = load_embodiment(REAL[0]).hand
    rm = dataclasses.replace(hand.real_model, mjcf={s: tmp_path / f"{s}.xml" for s in ("left", "right")})
    monkeypatch.setenv(MENAGERIE_ENV, str(tmp_path))      # an empty Menagerie root
    with pytest.raises(RealModelError) as err:
        load_model_spec(dataclasses.replace(hand, real_model=rm), "right")
    msg = str(err.value)
    assert str(hand.path) in msg and str(tmp_path / "right.xml") in msg and MENAGERIE_ENV in msg
    assert "mujoco_menagerie" in msg


@needs_models
def test_the_menagerie_root_wins_over_the_explicit_path(monkeypatch, tmp_path):
    hand = load_embodiment(REAL[0]).hand
    rm = dataclasses.replace(hand.real_model, mjcf={s: tmp_path / f"{s}.xml" for s in ("left", "right")})
    monkeypatch.setenv(MENAGERIE_ENV, _menagerie_root())
    spec = load_model_spec(dataclasses.replace(hand, real_model=rm), "left")
    assert spec.body(rm.name_prefix["left"] + rm.root_body) is not None


@needs_models
@pytest.mark.parametrize("name", REAL)
def test_pads_stand_proud_of_the_real_fingertips(name):
    """The pad geom is what touches objects (and the tactile surface lies on it): no part of the real
    fingertip may stick out past a pad's face."""
    model, data, _ = _home(name, "real")
    for s in load_embodiment(name).hand.tactile.sites:
        for side in ("left", "right"):
            site = model.site(f"{side}_{s.name}").id
            tip = model.body_parentid[model.body(f"{side}_{s.attach_body}").id]
            bodies = {b for b in range(model.nbody) if b == tip or model.body_parentid[b] == tip}
            beyond = _reach(model, data, bodies, data.site_xpos[site], data.site_xmat[site].reshape(3, 3)[:, 2])
            assert beyond < 0.0, (side, s.name, beyond)


@pytest.mark.parametrize("field, edit, expected", [
    ("joints", lambda b: b["joints"].pop(next(iter(b["joints"]))), "real_model.joints"),
    ("actuators", lambda b: b["actuators"].update({"extra": "nope"}), "real_model.actuators"),
    ("bodies", lambda b: b["bodies"].pop("palm"), "real_model.bodies"),
    ("mount", lambda b: b["mount"].pop("left"), "real_model.mount"),
])
def test_a_bad_real_model_block_names_the_file_and_the_field(tmp_path, monkeypatch, field, edit, expected):
    """The block is validated against the hand when the hand file loads, models present or not."""
    from sim.embodiment import description

    hand = load_embodiment(REAL[0]).hand
    with edited_catalog_file(monkeypatch, tmp_path, "hands", hand.name, lambda raw: edit(raw["real_model"])) as path:
        with pytest.raises(description.DescriptionError) as err:
            description.load_hand(hand.name)
    assert str(path) in str(err.value) and expected in str(err.value)
