"""The episode writer: small per-frame values are buffered and written at the end exactly as if they
had been appended frame by frame; large ones stream; a failed episode leaves no file."""

import h5py
import numpy as np
import pytest

from episodes.writer import SMALL_FRAME_BYTES, EpisodeWriter


def test_buffered_and_streamed_values_come_back_frame_by_frame(tmp_path):
    state = np.zeros(7)
    image = np.zeros((64, 64), np.float32)
    assert image.nbytes >= SMALL_FRAME_BYTES > state.nbytes
    with EpisodeWriter(tmp_path / "e.h5", {"meta/name": "x"}) as w:
        for k in range(5):
            state[:] = k                      # the same buffer, changed after each append
            image[:] = k
            frame = {"pose": state[:3], "image": image, "error": "bad" if k == 3 else ""}
            if k >= 2:
                frame["late"] = np.int64(10 + k)
            w.append(frame)
    with h5py.File(tmp_path / "e.h5") as f:
        assert f["pose"][:, 0].tolist() == [0, 1, 2, 3, 4] and f["pose"].maxshape == (None, 3)
        assert f["image"][:, 5, 5].tolist() == [0, 1, 2, 3, 4]
        assert [e.decode() for e in f["error"][()]] == ["", "", "", "bad", ""]
        assert f["late"][()].tolist() == [0, 0, 12, 13, 14]


def test_a_failed_episode_leaves_nothing(tmp_path):
    with pytest.raises(RuntimeError):
        with EpisodeWriter(tmp_path / "e.h5", {}) as w:
            w.append({"pose": np.zeros(3)})
            raise RuntimeError("render crashed")
    assert list(tmp_path.iterdir()) == []
