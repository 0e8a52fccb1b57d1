"""The episode writer: small per-frame values are buffered and written in blocks of frames exactly as if
they had been appended frame by frame; large ones stream; a failed episode leaves no file."""

import h5py
import numpy as np
import pytest

from episodes.writer import SMALL_BLOCK_FRAMES, SMALL_FRAME_BYTES, EpisodeWriter


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


def test_small_values_written_block_by_block_read_back_as_if_appended_frame_by_frame(tmp_path):
    """Over several blocks: a key that comes late, one that skips whole blocks and frames, values cast
    to the first frame's dtype as numpy casts them, and a final value over a key already written."""
    n = 3 * SMALL_BLOCK_FRAMES + 5
    gappy = [i for i in range(n) if i % 7 and not SMALL_BLOCK_FRAMES <= i < 2 * SMALL_BLOCK_FRAMES]
    with EpisodeWriter(tmp_path / "e.h5", {}) as w:
        for i in range(n):
            frame = {"step": np.int32(i), "flag": np.bool_(i % 2), "text": f"t{i}" if i % 5 == 0 else ""}
            if i in gappy:
                frame["gappy"] = np.array([i, -i], np.float32)
            if i >= SMALL_BLOCK_FRAMES + 3:
                frame["late"] = np.uint8(i) if i % 2 else np.int64(i + 254)     # cast to uint8: wraps
            if i == n - 1:
                frame["summary"] = np.arange(3)
            w.append(frame)
        w.write_final("step", np.int32(-1))
    expected_gappy = np.zeros((gappy[-1] + 1, 2), np.float32)
    expected_gappy[gappy] = np.array([[i, -i] for i in gappy])
    late = np.zeros(n, np.uint8)
    late[SMALL_BLOCK_FRAMES + 3:] = [np.uint8(i) if i % 2 else np.int64(i + 254).astype(np.uint8)
                                     for i in range(SMALL_BLOCK_FRAMES + 3, n)]
    with h5py.File(tmp_path / "e.h5") as f:
        assert f["step"][()] == -1
        assert f["flag"].dtype == bool and f["flag"][()].tolist() == [bool(i % 2) for i in range(n)]
        np.testing.assert_array_equal(f["gappy"][()], expected_gappy)
        assert f["late"].dtype == np.uint8
        np.testing.assert_array_equal(f["late"][()], late)
        assert f["summary"].shape == (n, 3) and not f["summary"][: n - 1].any()
        assert [t.decode() for t in f["text"][()]] == [f"t{i}" if i % 5 == 0 else "" for i in range(n)]


def test_a_failed_episode_leaves_nothing(tmp_path):
    with pytest.raises(RuntimeError):
        with EpisodeWriter(tmp_path / "e.h5", {}) as w:
            w.append({"pose": np.zeros(3)})
            raise RuntimeError("render crashed")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("first, later", [(np.zeros(3), np.zeros(2000)),        # small, then large
                                           (np.zeros((40, 40)), np.zeros((40, 41))),
                                           ("text", np.zeros(3))])
def test_a_frame_of_another_shape_is_refused_whole_and_names_the_key(tmp_path, first, later):
    path = tmp_path / "e.h5"
    with EpisodeWriter(path, {}) as w:
        w.append({"kept": np.float64(0), "changing": first})
        with pytest.raises(ValueError) as err:
            w.append({"kept": np.float64(1), "changing": later})
        w.append({"kept": np.float64(2), "changing": first})
    message = str(err.value)
    assert "e.h5" in message and "frame 1 of 'changing'" in message and "as in its first frame" in message
    with h5py.File(path) as f:         # nothing of the refused frame was written
        assert f["kept"][()].tolist() == [0.0, 2.0] and len(f["changing"]) == 2


def test_a_refused_frame_leaves_no_layout_for_its_new_keys(tmp_path):
    with EpisodeWriter(tmp_path / "e.h5", {}) as w:
        w.append({"a": np.zeros(3)})
        with pytest.raises(ValueError, match="'a'"):
            w.append({"c": np.zeros(5), "a": np.zeros(4)})       # c is new; a is refused
        w.append({"a": np.zeros(3), "c": np.zeros(7)})           # c's first written frame sets its shape
    with h5py.File(tmp_path / "e.h5") as f:
        assert f["c"].shape == (2, 7) and f["c"][0].tolist() == [0.0] * 7


def _pipeline(ds: h5py.Dataset) -> list[int]:
    dcpl = ds.id.get_create_plist()
    return [dcpl.get_filter(i)[0] for i in range(dcpl.get_nfilters())]


def test_images_use_the_plugin_codecs_and_a_join_keeps_them_chunk_for_chunk(tmp_path):
    import hdf5plugin

    from episodes.h5_concat import concat_frames

    rng = np.random.default_rng(0)
    frames = [{"rgb": rng.integers(0, 255, (48, 64, 3), np.uint8), "depth": rng.random((48, 64), np.float32),
               "mask": (rng.random((48, 64)) < 0.1).astype(np.uint16)} for _ in range(6)]
    for name, part in (("a.h5", frames[:4]), ("b.h5", frames[4:])):
        with EpisodeWriter(tmp_path / name, {}) as w:
            for frame in part:
                w.append(frame)
    concat_frames([tmp_path / "a.h5", tmp_path / "b.h5"], tmp_path / "joined.h5")
    with h5py.File(tmp_path / "a.h5") as a, h5py.File(tmp_path / "joined.h5") as f:
        # then HDF5's Fletcher-32 checksum of the stored chunk (issue 23: flipped bytes are refused on reading)
        assert _pipeline(f["rgb"]) == _pipeline(f["mask"]) == [hdf5plugin.ZSTD_ID, h5py.h5z.FILTER_FLETCHER32]
        assert _pipeline(f["depth"]) == [hdf5plugin.BLOSC_ID, h5py.h5z.FILTER_FLETCHER32]
        for key in ("rgb", "depth", "mask"):
            assert _pipeline(f[key]) == _pipeline(a[key]) and f[key].chunks == a[key].chunks
            np.testing.assert_array_equal(f[key][()], np.stack([fr[key] for fr in frames]))
            # the joined chunks are the parts' compressed bytes, not re-encoded
            assert f[key].id.read_direct_chunk((1,) + (0,) * (f[key].ndim - 1)) == \
                a[key].id.read_direct_chunk((1,) + (0,) * (a[key].ndim - 1))


def test_streams_grow_past_their_allocation_and_trim_to_the_frames_written(tmp_path):
    """A stream is grown 64 frames at a time and small images are written a block of frames at a time:
    150 frames, a key that starts late, one that stops early and one with a gap come back with exactly
    their frames (a missing frame is a zero row, as buffered values)."""
    image = np.zeros((32, 32), np.float32)
    with EpisodeWriter(tmp_path / "e.h5", {}) as w:
        for k in range(150):
            image[:] = k
            frame = {"image": image}
            if k >= 70:
                frame["late"] = image + 1000
            if k < 65:
                frame["early"] = image - 1
            if not 10 <= k < 13:
                frame["gap"] = image + 0.5
            w.append(frame)
    with h5py.File(tmp_path / "e.h5") as f:
        assert f["image"].shape == (150, 32, 32) and f["image"][:, 0, 0].tolist() == list(range(150))
        assert f["late"].shape == (150, 32, 32) and f["late"][:70].max() == 0
        assert f["late"][70:, 3, 3].tolist() == [1000 + k for k in range(70, 150)]
        assert f["early"].shape == (65, 32, 32) and f["early"][:, 1, 1].tolist() == [k - 1 for k in range(65)]
        assert f["gap"][:, 2, 2].tolist() == [0.0 if 10 <= k < 13 else k + 0.5 for k in range(150)]


def test_compressed_bytes_do_not_depend_on_blosc_threads(tmp_path):
    """Depth maps go through Blosc, whose output depends on its thread count; the writer pins it, so
    runs under any BLOSC_NTHREADS give the same chunk bytes (the manifest hashes the files)."""
    import os
    import subprocess
    import sys

    script = f"""
import hashlib, sys
sys.path.insert(0, {str(__import__('pathlib').Path(__file__).resolve().parents[1])!r})
import numpy as np, h5py
from episodes.writer import EpisodeWriter
depth = np.random.default_rng(0).random((5, 480, 640)).astype(np.float32) * 3   # paper-sized: Blosc splits it
with EpisodeWriter(sys.argv[1], {{}}) as w:
    for d in depth:
        w.append({{"depth": d}})
with h5py.File(sys.argv[1]) as f:
    ds = f["depth"]
    print(hashlib.sha256(b"".join(ds.id.read_direct_chunk(ds.id.get_chunk_info(i).chunk_offset)[1]
                                  for i in range(ds.id.get_num_chunks()))).hexdigest())
"""
    hashes = set()
    for threads, name in (("1", "a.h5"), ("4", "b.h5"), ("4", "c.h5")):
        env = {**os.environ, "BLOSC_NTHREADS": threads}
        out = subprocess.run([sys.executable, "-c", script, str(tmp_path / name)], env=env, check=True,
                             capture_output=True, text=True)
        hashes.add(out.stdout.strip())
    assert len(hashes) == 1


def test_a_frame_of_another_dtype_is_converted_by_hdf5_as_for_camera_images(tmp_path):
    """A small image stream created as uint8 and later given int64 values out of its range stores what
    HDF5's own conversion stores (clamped), not numpy's wrap-around."""
    first = np.zeros((64, 64), np.uint8)          # 4 kB a frame: streamed, in blocks of frames
    later = np.full((64, 64), 300, np.int64)
    later[0, :4] = [-1, 2, 255, 256]
    with EpisodeWriter(tmp_path / "e.h5", {}) as w:
        for value in (first, later, first):
            w.append({"mask": value})
    with h5py.File(tmp_path / "direct.h5", "w") as f:
        f.create_dataset("mask", data=np.zeros((1, 64, 64), np.uint8))[0] = later
        expected = f["mask"][0]
    with h5py.File(tmp_path / "e.h5") as f:
        np.testing.assert_array_equal(f["mask"][1], expected)
        assert f["mask"][1, 0, :4].tolist() == [0, 2, 255, 255]


def test_all_zero_frames_are_not_stored_and_read_back_as_zeros_also_after_a_join(tmp_path):
    """A tactile site out of contact or an empty mask is a frame of zero bytes: its chunk is left
    unallocated (no compression, no space) and reads back as zeros; a join keeps it so. -0.0 is not
    zero bytes and is stored."""
    from episodes.h5_concat import concat_frames

    ones, negative_zero = np.ones((64, 64), np.float32), np.full((64, 64), -0.0, np.float32)
    zeros, contact = np.zeros((64, 64), np.float32), np.zeros((64, 64), np.float32)
    contact[31, 17] = 1e-3                        # one pixel in the middle: neither the first nor the last byte
    frames = [zeros, ones, zeros, negative_zero, contact, zeros]
    for name, part in (("a.h5", frames[:3]), ("b.h5", frames[3:])):
        with EpisodeWriter(tmp_path / name, {}) as w:
            for image in part:
                w.append({"tactile": image, "mask": (image != 0).astype(np.uint8)})
    concat_frames([tmp_path / "a.h5", tmp_path / "b.h5"], tmp_path / "joined.h5")
    with h5py.File(tmp_path / "a.h5") as a, h5py.File(tmp_path / "joined.h5") as f:
        assert a["tactile"].id.get_num_chunks() == 1
        stored = [f["tactile"].id.get_chunk_info(i).chunk_offset[0] for i in range(f["tactile"].id.get_num_chunks())]
        assert stored == [1, 3, 4] and f["mask"].id.get_num_chunks() == 2
        assert f["tactile"][()].tobytes() == np.stack(frames).tobytes()      # -0.0 kept bit for bit
        np.testing.assert_array_equal(f["mask"][()], np.stack([fr != 0 for fr in frames]).astype(np.uint8))


@pytest.mark.parametrize("shape, dtype", [((65, 65), np.uint8), ((7,), np.float64), ((3, 5), np.int16), ((0,), np.uint8)])
def test_the_zero_check_looks_at_every_byte(shape, dtype):
    """Odd lengths (a tail after the 8-byte words), a single non-zero byte anywhere."""
    from episodes.writer import _all_zero_bytes

    value = np.zeros(shape, dtype)
    assert _all_zero_bytes(value) and _all_zero_bytes(value[::-1])
    raw = value.reshape(-1).view(np.uint8)
    for i in range(raw.size):
        raw[i] = 1
        assert not _all_zero_bytes(value), i
        raw[i] = 0


def test_only_one_frame_image_chunks_go_without_a_chunk_cache(tmp_path):
    """Image rows are whole chunks, written once: no cache. A large 1-D row shares 256-frame chunks, and
    without a cache every append would decompress and recompress its chunk."""
    with EpisodeWriter(tmp_path / "e.h5", {}) as w:
        for _ in range(3):
            w.append({"image": np.ones((64, 64), np.float32), "row": np.ones(2000, np.float32)})
        image, row = w.file["image"], w.file["row"]
        assert image.chunks[0] == 1 and image.id.get_access_plist().get_chunk_cache()[1] == 0
        assert row.chunks[0] == 256 and row.id.get_access_plist().get_chunk_cache()[1] > 0
