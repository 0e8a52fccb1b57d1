import numpy as np
import pytest

from tactile.heatmap import tacmap_panel


def test_panel_is_an_rgb_grid_with_one_tile_per_site():
    maps = {f"rh_site{i}": np.zeros((30, 30), np.uint8) for i in range(7)}
    maps["rh_site3"][10:20, 10:20] = 200
    panel = tacmap_panel(maps, title="episode 3, frame 120")
    assert panel.dtype == np.uint8 and panel.ndim == 3 and panel.shape[2] == 3
    # 7 sites -> 5 columns x 2 rows of 180 px tiles (30 px scaled by 6).
    assert panel.shape[1] >= 5 * 180 and panel.shape[0] >= 2 * 180
    assert (panel.reshape(-1, 3) != 255).any(axis=1).sum() > 7 * 180 * 180 * 0.9  # tiles drawn
    hot = panel[:, :, 0].astype(int) - panel[:, :, 2].astype(int)
    assert hot.max() > 100  # the contact patch shows in warm colours


def test_panel_is_deterministic_and_checks_inputs():
    maps = {"a": np.arange(64, dtype=np.uint8).reshape(8, 8), "b": np.zeros((8, 8), np.uint8)}
    assert tacmap_panel(maps).tobytes() == tacmap_panel(maps).tobytes()
    with pytest.raises(ValueError, match="at least one"):
        tacmap_panel({})
    with pytest.raises(ValueError, match="one shape"):
        tacmap_panel({"a": np.zeros((8, 8), np.uint8), "b": np.zeros((9, 8), np.uint8)})
    with pytest.raises(ValueError, match="uint8"):
        tacmap_panel({"a": np.zeros((8, 8), np.float32)})
