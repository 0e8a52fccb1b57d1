"""Raw -> replay -> render -> HDF5 episode in the paper's layout; schema validation; reader."""

import h5py
import numpy as np
import pytest

from episodes.reader import EpisodeReader
from episodes.stages import raw_to_episode
from episodes.validate import validate_episode
from sim.registry import sensor_profile

CAMERAS = ("chest", "overhead", "stereo_left", "stereo_right", "left_wrist", "right_wrist")


@pytest.fixture(scope="module")
def episode(raw_path, tmp_path_factory):
    return raw_to_episode(raw_path, sensor_profile("preview"), tmp_path_factory.mktemp("episodes"))


def test_episode_has_the_paper_layout(episode):
    assert validate_episode(episode) == []
    with h5py.File(episode) as f:
        for group in ("meta", "time", "episode", "action", "cameras", "robot", "objects", "metrics"):
            assert group in f, group
        assert set(f["cameras"]) == set(CAMERAS)
        T = f["time/frame_index"].shape[0]
        assert T == 3    # 18 control steps at 60 Hz, 10 Hz preview -> frames after steps 6, 12, 18
        rgb, depth = f["cameras/chest/rgb"], f["cameras/chest/depth_m"]
        assert rgb.shape == (T, 96, 128, 3) and rgb.dtype == np.uint8
        assert depth.shape == (T, 96, 128) and depth.dtype == np.float32
        assert rgb[()].std() > 5                      # a real image, not a blank
        assert 0.05 < float(np.median(depth[()])) < 5.0
        assert f["cameras/chest/extrinsic_world_from_cam"].shape == (T, 4, 4)
        assert f["objects/lemon_1/pose_world"].shape == (T, 7)
        assert list(f["time/sim_step"][()]) == [6, 12, 18]


def test_reader_loads_a_frame_range(episode):
    with EpisodeReader(episode) as r:
        assert r.num_frames == 3
        part = r.read("cameras/overhead/rgb", 1, 3)
        assert part.shape[0] == 2
        assert r.meta("task") == "citrus_plate_loading"
        assert "lscr" in r.metrics()


def test_validator_reports_what_is_missing(episode, tmp_path):
    broken = tmp_path / "episode_broken.hdf5"
    broken.write_bytes(episode.read_bytes())
    with h5py.File(broken, "a") as f:
        del f["robot/qpos"]
        del f["cameras/chest/depth_m"]
    problems = validate_episode(broken)
    assert any("robot/qpos" in p for p in problems)
    assert any("cameras/chest/depth_m" in p for p in problems)


def test_rendering_is_deterministic(raw_path, tmp_path):
    a = raw_to_episode(raw_path, sensor_profile("preview"), tmp_path / "a")
    b = raw_to_episode(raw_path, sensor_profile("preview"), tmp_path / "b")
    with h5py.File(a) as fa, h5py.File(b) as fb:
        assert fa["cameras/chest/rgb"][()].tobytes() == fb["cameras/chest/rgb"][()].tobytes()
        assert fa["robot/qpos"][()].tobytes() == fb["robot/qpos"][()].tobytes()
