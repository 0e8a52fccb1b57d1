"""`b2d bench replay` accounts for every millisecond of a frame once: the per-frame parts add up to the
per-frame time, the once-per-file set-up is reported apart, and the unavoidable share counts only the
GL passes and tactile ray casting (decoding the GL buffers is overhead)."""

import pytest

from b2d_cli.benchmarks import UNAVOIDABLE_RENDER_PARTS, bench_replay


def test_replay_bench_parts_add_up_and_setup_is_reported_apart():
    out = bench_replay("preview", steps=24)
    share = out["share"]
    assert "render_setup" not in share and out["one_off_per_render_file_ms"]["render_setup"] > 0
    assert sum(share.values()) == pytest.approx(1.0, abs=0.01)
    assert "render_camera_decode" in share and "camera_decode" not in UNAVOIDABLE_RENDER_PARTS
    unavoidable = sum(share[f"render_{k}"] for k in UNAVOIDABLE_RENDER_PARTS if f"render_{k}" in share)
    assert out["unavoidable_render_and_raycast_share"] == pytest.approx(unavoidable, abs=0.002)
    assert out["antialias"] is False and out["shadows"] is False
    # each label has its own share (preview lists box2d, box3d and occupancy; box2d needs the masks)
    assert {"render_labels_segmentation", "render_labels_box2d", "render_labels_box3d",
            "render_labels_occupancy"} <= share.keys() and "render_labels" not in share
    # issue 22: CPU-time figures (robust to other processes on the cores) and, as preview sets its own
    # tessellation, the same cameras at MuJoCo's default measured in the same run
    assert out["frames_per_cpu_second"] > 0 and out["load_average_1min"] >= 0
    assert out["re_render_frames_per_cpu_second"] > out["frames_per_cpu_second"]     # the replay is not redone
    versus = out["tessellation_vs_mujoco_default"]
    assert versus["tessellation"] == [8, 4] and versus["mujoco_default"] == [28, 16]
    assert versus["camera_cpu_ms_per_frame"] > 0 and versus["camera_cpu_ms_per_frame_mujoco_default"] > 0
    assert 0 < versus["rgb_pixels_changed"] < 0.5 and 0 <= versus["depth_pixels_changed_over_2mm"] < 0.5
    # issue 22: the still cameras' kept layers against whole passes (the code before them), same run
    layers = out["still_layers_vs_whole_passes"]
    assert layers["images_identical"] is True
    assert layers["still_cameras"] == ["chest", "overhead", "stereo_left", "stereo_right"]
    assert layers["camera_cpu_ms_per_frame"] > 0 and layers["camera_cpu_ms_per_frame_whole_passes"] > 0
    assert layers["frames_per_cpu_second_whole_passes"] > 0 and layers["frames_per_cpu_second_speedup"] > 0
