"""Tactile in HDF5 episodes (real scripted grasps, replayed and sensed), and `b2d tactile show`."""

import copy
import json

import cv2
import h5py
import mujoco
import numpy as np
import pytest
from click.testing import CliRunner

from b2d_cli.main import cli
from episodes import schema
from episodes.raw import read_raw
from episodes.stages import assemble_episode, raw_to_episode, render_to_file
from episodes.validate import validate_episode
from sim.registry import parse_sensor_profile, sensor_profile
from sim.replay import scene_for
from tactile.quantize import encode_tacmap
from tactile.targets import geom_mesh, geom_raycaster, target_geoms

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"
GRASP_STEPS = 420  # the scripted operator's first grasp (a fingertip on a fruit) falls well inside
RATE_HZ = 2        # one frame every 30 control steps: 14 frames
ROOT = schema.TACTILE_ROOT


def small_profile(tactile: bool = True):
    """Preview's tactile block with one small camera at 2 Hz, so the frames stay cheap."""
    raw = copy.deepcopy(sensor_profile("preview").raw)
    raw.update(name="preview_one_camera", rate_hz=RATE_HZ)
    raw["cameras"].update(ids=["overhead"], width=64, height=48)
    raw["tactile"]["enabled"] = tactile
    return parse_sensor_profile(raw)


@pytest.fixture(scope="module")
def grasp_raw(tmp_path_factory):
    from teleop.demos import record_demonstrations

    [rec] = record_demonstrations(TASK, EMBODIMENT, 1, tmp_path_factory.mktemp("grasp"), max_steps=GRASP_STEPS)
    assert rec.error is None, rec.error
    return rec.path


@pytest.fixture(scope="module")
def episode(grasp_raw, tmp_path_factory):
    return raw_to_episode(grasp_raw, small_profile(), tmp_path_factory.mktemp("tactile_episode"))


def tactile_arrays(path) -> dict:
    """Every dataset under robot/tactile: raw bytes for numbers, the values for strings."""
    out = {}

    def keep(name, obj):
        if isinstance(obj, h5py.Dataset):
            value = obj[()]
            out[name] = value.tobytes() if isinstance(value, np.ndarray) and value.dtype.kind != "O" else repr(value)

    with h5py.File(path) as f:
        f[ROOT].visititems(keep)
    return out


def test_episode_with_tactile_validates_and_has_the_declared_layout(episode):
    assert validate_episode(episode) == []
    with h5py.File(episode) as f:
        T = f["time/frame_index"].shape[0]
        assert T == GRASP_STEPS * RATE_HZ // 60
        assert "tactile" in json.loads(f["meta/modalities"][()])
        sites = [s.decode() for s in f[f"{ROOT}/site_names"][()]]
        assert len(sites) == 10 and sites[0] == "left_thumb_tip" and sites[-1] == "right_little_tip"
        for site in sites:
            for kind, dtype in (("tacmap", np.uint8), ("distance_along_normal_m", np.float32),
                                ("contact_mask", np.bool_)):
                ds = f[schema.tactile_path(kind, site)]
                assert ds.shape == (T, 30, 30) and ds.dtype == dtype, (kind, site)
            assert f[f"{ROOT}/surface/{site}/point_mm"].shape == (30, 30, 3)
        meta = json.loads(f[f"{ROOT}/meta"][()])
        assert meta["step"] == 8 and meta["shape"] == [30, 30] and meta["max_range_m"] == pytest.approx(0.015)
        assert meta["encoding"]["smoothing"]["kernel"] == 1 and meta["encoding"]["saturation_mm"] == pytest.approx(5.15)
        # only task objects are ray targets: never the robot, the table or the floor
        assert meta["targets"] == ["plate", "lemon_1", "lemon_2", "orange_1", "orange_2"]
        assert {s["attach_body"] for s in meta["sites"]} >= {"left_thumb_distal", "right_index_intermediate"}
        # the left hand's surface is the right hand's mirrored through the attach-body yz plane
        right = f[f"{ROOT}/surface/right_index_tip/point_mm"][()]
        left = f[f"{ROOT}/surface/left_index_tip/point_mm"][()]
        assert np.array_equal(left, right * np.float32([-1, 1, 1]) + 0) and np.abs(right).max() > 1
        # the hand file's grouping policy: side-specific thumb/4F, one asset per group and side
        assert meta["grouping"] == "side_specific"
        assets = {s["name"]: s["asset"] for s in meta["sites"]}
        assert assets["right_index_tip"] == assets["right_little_tip"] == "R4F" and assets["left_thumb_tip"] == "LTH"
        little = f[f"{ROOT}/surface/right_little_tip/point_mm"][()]
        assert np.array_equal(little, right)


def test_fingertip_pressing_an_object_gives_tactile_and_free_frames_are_zero(grasp_raw, episode):
    raw = read_raw(grasp_raw)
    scene = scene_for(raw)
    model, data = scene.model, mujoco.MjData(scene.model)
    with h5py.File(episode.parent / ".work" / grasp_raw.name.replace(".raw.h5", ".replay.h5")) as rep:
        qpos = rep["qpos"][()]
    with h5py.File(episode) as f:
        steps = f["time/sim_step"][()] - 1
        sites = [s.decode() for s in f[f"{ROOT}/site_names"][()]]
        tacmap = np.stack([f[schema.tactile_path("tacmap", s)][()] for s in sites], axis=1)
        depth = np.stack([f[schema.tactile_path("distance_along_normal_m", s)][()] for s in sites], axis=1)
        mask = np.stack([f[schema.tactile_path("contact_mask", s)][()] for s in sites], axis=1)
        targets = json.loads(f[f"{ROOT}/meta"][()])["targets"]
    object_geoms = {model.geom(n).id for n in targets}
    pads = {model.geom(f"{s}_pad").id: i for i, s in enumerate(sites)}
    pressed = []  # (frame, site) where MuJoCo reports the site's pad touching an object
    for k, step in enumerate(steps):
        data.qpos[:] = qpos[step]
        mujoco.mj_forward(model, data)
        for c in data.contact[: data.ncon]:
            for pad, other in ((c.geom1, c.geom2), (c.geom2, c.geom1)):
                if pad in pads and other in object_geoms:
                    pressed.append((k, pads[pad]))
    assert pressed and all(k > 0 for k, _ in pressed)
    # frame 0 is the home pose: nothing touches anything
    assert not tacmap[0].any() and not depth[0].any() and not mask[0].any()
    assert any(tacmap[k, s].max() > 0 and mask[k, s].any() for k, s in pressed)
    # the three arrays agree: depth only where the contact check passed, within range, encoded as stored
    assert np.array_equal(mask, depth > 0) and depth.max() <= 0.015
    for k in range(len(steps)):
        for s in range(len(sites)):
            assert np.array_equal(tacmap[k, s], encode_tacmap(depth[k, s], mask[k, s], 8))


def test_a_sphere_pressed_1mm_into_one_pad_shows_on_that_site_only(grasp_raw):
    from sim.embodiment import load_embodiment
    from sim.render import set_positions
    from tactile.rig import TactileRig

    scene = scene_for(read_raw(grasp_raw))
    model, data = scene.model, scene.home_data()
    rig = TactileRig.for_profile(scene, small_profile())
    assert not rig.capture(data).mask.any()  # home pose: the hands touch nothing
    pad = next(s.pad for s in load_embodiment(EMBODIMENT).hand.tactile.sites if s.name == "index_tip")
    body = model.body("right_index_intermediate").id
    rot, pos = data.xmat[body].reshape(3, 3), data.xpos[body]
    radius = model.geom_size[model.geom("orange_1").id][0]
    centre = pos + rot @ (np.asarray(pad.center) + np.asarray(pad.normal) * (radius - 0.001))
    qpos = data.qpos.copy()
    qpos[scene.object_qpos_adr["orange_1"]:][:7] = [*centre, 1, 0, 0, 0]
    set_positions(model, data, qpos)
    frame = rig.capture(data)
    touched = [n for n, m in zip(frame.site_names, frame.mask) if m.any()]
    assert touched == ["right_index_tip"]
    s = frame.site_names.index("right_index_tip")
    # deepest at the pad centre: 1 mm less the grid's offset from it (cells are ~1.1 mm apart at step 8)
    assert 0.0009 < frame.distance_m[s].max() <= 0.001 + 1e-6
    assert frame.tacmap[s].max() == encode_tacmap(frame.distance_m[s], frame.mask[s], 8).max() > 100


def test_same_raw_gives_byte_identical_tactile(grasp_raw, episode, tmp_path):
    """A second render of the same replay, with the surface maps and ray targets built afresh, gives
    byte-identical tactile arrays. (Within one process; the cross-process check is for replay,
    tests/test_replay.py.)"""
    from tactile.rig import clear_caches

    clear_caches()
    replay_path = episode.parent / ".work" / grasp_raw.name.replace(".raw.h5", ".replay.h5")
    profile = small_profile()
    render_to_file(replay_path, profile, tmp_path / "again.render.h5")
    again = tmp_path / episode.name
    assemble_episode(replay_path, tmp_path / "again.render.h5", profile, again)
    first, second = tactile_arrays(episode), tactile_arrays(again)
    assert first.keys() == second.keys() and len(first) == 10 * 5 + 2
    assert all(first[k] == second[k] for k in first)
    assert any(np.frombuffer(v, np.uint8).any() for k, v in first.items() if k.startswith("tacmap/"))
    assert first["meta"] == second["meta"] and "right_index_tip" in first["site_names"]


def test_validator_requires_tactile_when_the_profile_enables_it(episode, tmp_path):
    broken = tmp_path / "episode_broken.hdf5"
    broken.write_bytes(episode.read_bytes())
    with h5py.File(broken, "a") as f:
        del f[schema.tactile_path("contact_mask", "right_index_tip")]
        f[schema.tactile_path("tacmap", "left_ring_tip")][0, 0, 0] = 0  # in place: still valid
        f.create_dataset(schema.tactile_path("tacmap", "palm"), data=np.zeros((1, 30, 30), np.uint8))
    problems = validate_episode(broken)
    assert any(p.startswith(f"{ROOT}/contact_mask/right_index_tip: missing") for p in problems), problems
    assert any("palm" in p and "site_names" in p for p in problems), problems
    with h5py.File(broken, "a") as f:
        del f[ROOT]
    assert any(p.startswith(f"{ROOT}/: missing although meta/modalities") for p in validate_episode(broken))


def test_profile_without_tactile_writes_and_validates_without_it(raw_path, tmp_path):
    path = raw_to_episode(raw_path, small_profile(tactile=False), tmp_path, max_frames=1)
    assert validate_episode(path) == []
    with h5py.File(path) as f:
        assert ROOT not in f and "tactile" not in json.loads(f["meta/modalities"][()])


def test_targets_are_the_object_subtrees_and_meshes_match_the_geoms():
    spec = mujoco.MjSpec()
    spec.worldbody.add_body(name="table").add_geom(name="table_top", type=mujoco.mjtGeom.mjGEOM_BOX, size=[1, 1, 0.1])
    spec.worldbody.add_body(name="robot").add_geom(name="finger", type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[0.01, 0.02, 0])
    box = spec.worldbody.add_body(name="box", pos=[0, 0, 1])
    box.add_geom(name="box_base", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.1, 0.05, 0.02])
    lid = box.add_body(name="box/lid", pos=[0, 0, 0.03])
    lid.add_joint(name="box/lid", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[1, 0, 0])
    lid.add_geom(name="lid", type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[0.05, 0.01, 0])
    lid.add_geom(name="knob", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.03, 0, 0])
    spec.add_mesh(name="tetra", uservert=[0, 0, 0, 0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1], userface=[0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3])
    spec.worldbody.add_body(name="toy", pos=[1, 0, 1]).add_geom(name="toy", type=mujoco.mjtGeom.mjGEOM_MESH, meshname="tetra")
    model = spec.compile()
    assert [n for n, _ in target_geoms(model, ["box", "toy"])] == ["box_base", "lid", "knob", "toy"]
    knob_id = model.geom("knob").id  # equal primitives share one (read-only) ray-cast scene
    assert geom_raycaster(model, knob_id) is geom_raycaster(model, knob_id)

    def mesh(name):
        return geom_mesh(model, model.geom(name).id)

    assert np.allclose(mesh("box_base").bounds, [[-0.1, -0.05, -0.02], [0.1, 0.05, 0.02]])
    knob = mesh("knob")  # vertices on the sphere, faces no deeper than one fine quantizer level (5 um)
    assert np.allclose(np.linalg.norm(knob.vertices, axis=1), 0.03)
    assert np.linalg.norm(knob.triangles_center, axis=1).min() > 0.03 - 5e-6
    lid = mesh("lid")
    assert np.allclose(lid.bounds, [[-0.05, -0.05, -0.01], [0.05, 0.05, 0.01]], atol=5e-6)
    toy = mesh("toy")  # mesh geoms come out in the geom frame, as compiled
    assert len(toy.faces) == 4 and toy.is_watertight
    with pytest.raises(ValueError, match="cannot be a tactile target"):
        spec2 = mujoco.MjSpec()
        spec2.worldbody.add_geom(name="ground", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[1, 1, 0.1])
        m2 = spec2.compile()
        geom_mesh(m2, 0)


# ---------------------------------------------------------------- b2d tactile show


def test_show_writes_one_heatmap_per_site(episode, tmp_path):
    with h5py.File(episode) as f:
        sites = [s.decode() for s in f[f"{ROOT}/site_names"][()]]
        peak = np.stack([f[schema.tactile_path("tacmap", s)][()].max(axis=(1, 2)) for s in sites]).max(axis=0)
        touched = int(np.argmax(peak))
        assert peak[0] == 0 and peak[touched] > 50
    pngs = []
    for frame in (0, touched):
        out = tmp_path / f"frame{frame}.png"
        result = CliRunner().invoke(cli, ["tactile", "show", str(episode), "--frame", str(frame), "--out", str(out)])
        assert result.exit_code == 0, result.output
        assert result.output.strip() == str(out)
        pngs.append(cv2.imread(str(out)))
    blank, contact = pngs
    # 2 rows (left, right hand) x 5 sites of 30 px tiles scaled to 180 px, plus labels and a title
    assert blank.shape[0] > 2 * 180 and blank.shape[1] > 5 * 180 and blank.shape == contact.shape
    # tiles are black without contact; contact shows in saturated colours (text is grey, background white)
    def coloured(image):
        return int((image.max(axis=2).astype(int) - image.min(axis=2) > 40).sum())

    assert coloured(blank) == 0 and coloured(contact) >= 36  # at least one 6 x 6 px cell


def test_show_default_output_name(episode, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(cli, ["tactile", "show", str(episode), "--frame", "1"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / f"{episode.stem}_tactile_00001.png").is_file()


def test_show_bad_inputs_give_one_clear_line(episode, tmp_path):
    no_tactile = tmp_path / "episode_no_tactile.hdf5"
    no_tactile.write_bytes(episode.read_bytes())
    with h5py.File(no_tactile, "a") as f:
        del f[ROOT]
    junk = tmp_path / "junk.hdf5"
    junk.write_bytes(b"not hdf5")
    cases = [
        ([str(tmp_path / "missing.hdf5"), "--frame", "0"], ["missing.hdf5", "<file>", "existing"]),
        ([str(junk), "--frame", "0"], ["junk.hdf5", "not HDF5"]),
        ([str(no_tactile), "--frame", "0"], ["episode_no_tactile.hdf5", f"'{ROOT}'", "without tactile"]),
        ([str(episode), "--frame", "999"], [episode.name, "'--frame'", "[0, 13]", "999"]),
        ([str(episode), "--frame", "-1"], [episode.name, "'--frame'"]),
    ]
    for args, words in cases:
        result = CliRunner().invoke(cli, ["tactile", "show", *args, "--out", str(tmp_path / "x.png")])
        assert result.exit_code == 2, result.output
        lines = result.output.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("error: "), result.output
        assert all(w in lines[0] for w in words), (words, lines[0])
    assert not (tmp_path / "x.png").exists()
