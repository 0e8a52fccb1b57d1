"""`b2d export usd`: the episode's motion as an animated USD stage, posed from the full qpos."""

import h5py
import mujoco
import numpy as np
import pytest
from click.testing import CliRunner
from pxr import Tf, Usd, UsdGeom

from b2d_cli.main import cli
from episode_media.qpos import episode_qpos
from episode_media.source import episode_scene
from episodes.reader import open_episode
from episode_media.usd_export import export_usd
from episodes.raw import read_raw
from sim.errors import SpecError
from sim.replay import replay


@pytest.fixture(scope="module")
def exported(tiny_episode, tmp_path_factory):
    return export_usd(tiny_episode, tmp_path_factory.mktemp("usd") / "out")


@pytest.fixture(scope="module")
def model(tiny_episode):
    with open_episode(tiny_episode) as reader:
        return episode_scene(reader).model


def test_episode_qpos_is_the_replayed_state_of_each_frame(tiny_episode, raw_path, model):
    qpos = episode_qpos(tiny_episode, model)
    with h5py.File(tiny_episode) as f:
        steps = f["time/sim_step"][()] - 1          # sim_step counts control steps from 1
    replayed = replay(read_raw(raw_path)).qpos[steps]
    assert qpos.shape == (3, model.nq)
    np.testing.assert_array_equal(qpos, replayed)


def test_the_stage_has_one_time_sample_per_frame_and_moving_bodies_move(exported, tiny_episode, model):
    assert exported.frames == 3 and exported.path.is_file()
    stage = Usd.Stage.Open(str(exported.path))
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (0, 2)
    assert stage.GetTimeCodesPerSecond() == pytest.approx(10.0)       # the episode's 10 Hz frames
    # the geom that moves most over the episode, from an independent kinematics pass
    data, positions = mujoco.MjData(model), []
    for q in episode_qpos(tiny_episode, model):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        positions.append(data.geom_xpos.copy())
    positions = np.array(positions)
    gid = int(np.argmax(np.linalg.norm(positions[-1] - positions[0], axis=1)))
    assert np.linalg.norm(positions[-1, gid] - positions[0, gid]) > 1e-3
    name = Tf.MakeValidIdentifier(f"{model.geom(gid).name}_id{gid}_geom")
    prim = next(p for p in stage.Traverse() if p.GetName().endswith(name) and "Xform" in p.GetName())
    xform = UsdGeom.Xformable(prim)
    samples = [a for a in prim.GetAttributes() if a.GetName().startswith("xformOp:transform")][0].GetTimeSamples()
    assert list(samples) == [0.0, 1.0, 2.0]
    for t in range(3):
        world = np.array(xform.ComputeLocalToWorldTransform(Usd.TimeCode(t)))
        np.testing.assert_allclose(world[3, :3], positions[t, gid], atol=1e-5)   # USD matrices are row-vector


def test_the_cli_writes_a_frame_range_and_replaces_its_own_output(tiny_episode, tmp_path):
    out, written = tmp_path / "usd", []
    stage_file = out / "frames" / f"{tiny_episode.stem}.usda"
    for _ in range(2):      # the second run replaces the first output, byte for byte
        result = CliRunner().invoke(cli, ["export", "usd", str(tiny_episode), "--out", str(out),
                                          "--frames", "1:3", "--format", "usda"])
        assert result.exit_code == 0, result.output
        written.append(stage_file.read_bytes())
    assert written[0] == written[1]
    assert result.stdout.strip() == str(stage_file)
    stage = Usd.Stage.Open(str(stage_file))
    assert stage.GetEndTimeCode() == 1
    assert stage.GetRootLayer().customLayerData["b2d_first_frame"] == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["usd"]    # no temporary folders left


def test_a_missing_object_pose_is_named(tiny_episode, model, tmp_path):
    broken = tmp_path / "episode_broken.hdf5"
    broken.write_bytes(tiny_episode.read_bytes())
    with h5py.File(broken, "a") as f:
        del f["objects/lemon_1/pose_world"]
    with pytest.raises(SpecError, match="objects/lemon_1/pose_world") as err:
        episode_qpos(broken, model)
    assert str(broken) in str(err.value)


def test_export_refuses_to_replace_a_folder_it_did_not_write(tiny_episode, tmp_path):
    (tmp_path / "notes.txt").write_text("keep me")
    result = CliRunner().invoke(cli, ["export", "usd", str(tiny_episode), "--out", str(tmp_path)])
    assert result.exit_code == 2 and "--out" in result.output
    assert (tmp_path / "notes.txt").read_text() == "keep me"
