"""The labels benchmark runs end to end on a small profile and reports every figure."""

import pytest

from sim.labels.bench import run_bench


def test_label_bench_reports_each_label_against_rgb():
    out = run_bench("preview", frames=1)
    ms = out["ms_per_frame"]
    for key in ("rgb", "depth", "depth_and_geom_ids", "segmentation_masks", "box2d", "box3d", "occupancy"):
        assert ms[key] > 0, key
    assert out["occupancy_grid"] == [30, 20, 15] and out["cameras"] == 6 and out["objects"] == 5
    parts = ("segmentation_render_next_to_depth", "segmentation_masks", "box2d", "box3d", "occupancy")
    assert out["labels_ms_per_frame"] == pytest.approx(sum(ms[k] for k in parts), abs=0.01)
    assert isinstance(out["labels_vs_rgb_ratio"], float)
