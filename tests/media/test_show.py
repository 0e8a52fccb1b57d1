"""`b2d show`: cameras at their stored pixels with the tactile heatmaps beside them, as PNG or MP4."""

import cv2
import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from b2d_cli.main import cli
from episode_media.strip import compose_frame, show_episode
from episodes import schema
from tactile.heatmap import tacmap_panel


def _stored(episode):
    with h5py.File(episode) as f:
        rgb = {cam: f[f"cameras/{cam}/rgb"][()] for cam in ("chest", "overhead")}
        sites = [s.decode() for s in f["robot/tactile/site_names"][()]]
        tacmaps = {s: f[schema.tactile_path("tacmap", s)][()] for s in sites}
    return rgb, tacmaps


def _found_exactly(image: np.ndarray, tile: np.ndarray) -> bool:
    """`tile` appears in `image` pixel for pixel (best match located by OpenCV, then compared exactly)."""
    scores = cv2.matchTemplate(image, tile, cv2.TM_SQDIFF)
    y, x = np.unravel_index(np.argmin(scores), scores.shape)
    return np.array_equal(image[y: y + tile.shape[0], x: x + tile.shape[1]], tile)


def test_the_png_strip_holds_each_frame_with_stored_pixels_and_heatmaps(tiny_episode, tmp_path):
    result = CliRunner().invoke(cli, ["show", str(tiny_episode), "--out", str(tmp_path / "s.png")])
    assert result.exit_code == 0, result.output
    assert "PNG strip of 3 frames" in result.stderr
    strip = cv2.cvtColor(cv2.imread(str(tmp_path / "s.png")), cv2.COLOR_BGR2RGB)
    rgb, tacmaps = _stored(tiny_episode)
    panel = tacmap_panel({s: m[0] for s, m in tacmaps.items()}, title="tactile (TacMap)", columns=5)
    # one frame: header, two 64x48 cameras side by side, the 2 x 5 heatmap panel to their right
    frame_w = 6 + 2 * (64 + 6) + panel.shape[1]
    frame_h = 28 + max(18 + 48 + 6, panel.shape[0])
    assert strip.shape == (3 * (frame_h + frame_h % 2), frame_w + frame_w % 2, 3)
    rows = np.split(strip, 3, axis=0)
    for k, row in enumerate(rows):
        for cam, frames in rgb.items():
            assert _found_exactly(row, frames[k]), (cam, k)
        assert _found_exactly(row, tacmap_panel({s: m[k] for s, m in tacmaps.items()}, title="tactile (TacMap)",
                                                columns=5))
    assert not np.array_equal(rgb["chest"][0], rgb["chest"][2])      # the arm moves: frames stay in order
    assert not _found_exactly(rows[0], rgb["chest"][2])


def test_the_mp4_has_one_video_frame_per_chosen_frame(tiny_episode, tmp_path):
    shown = show_episode(tiny_episode, tmp_path / "v.mp4", frames="0:3", stride=2)
    assert shown.kind == "mp4" and shown.frames == 2 and shown.fps == pytest.approx(5.0)
    video = cv2.VideoCapture(str(shown.path))
    assert video.isOpened()
    assert int(video.get(cv2.CAP_PROP_FRAME_COUNT)) == 2
    count = 0
    while video.read()[0]:
        count += 1
    assert count == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["v.mp4"]      # no temporary file left


def test_an_unavailable_codec_falls_back_to_a_png_strip(tiny_episode, tmp_path):
    shown = show_episode(tiny_episode, tmp_path / "v.mp4", frames="1:2", fourcc="ZZZZ")
    assert shown.kind == "png" and shown.path == tmp_path / "v.png" and "PNG strip instead" in shown.note
    assert cv2.imread(str(shown.path)) is not None
    assert sorted(p.name for p in tmp_path.iterdir()) == ["v.png"]


def test_a_frame_without_tactile_is_just_the_cameras():
    cams = {"a": np.full((10, 20, 3), 7, np.uint8), "b": np.full((10, 20, 3), 9, np.uint8)}
    image = compose_frame("header", cams, None, columns=1)       # one column: b below a
    assert image.shape == (28 + 2 * (18 + 10 + 6), 6 + 20 + 6, 3)
    assert (image[28 + 18: 28 + 28, 6: 26] == 7).all() and (image[28 + 34 + 18: 28 + 34 + 28, 6: 26] == 9).all()


def test_camera_scale_enlarges_tiles_by_whole_pixels(tiny_episode, tmp_path):
    shown = show_episode(tiny_episode, tmp_path / "big.png", frames="2:3", camera_scale=2)
    image = cv2.cvtColor(cv2.imread(str(shown.path)), cv2.COLOR_BGR2RGB)
    rgb, _ = _stored(tiny_episode)
    assert _found_exactly(image, np.repeat(np.repeat(rgb["overhead"][2], 2, axis=0), 2, axis=1))
