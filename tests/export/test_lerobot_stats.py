"""Feature statistics: images from exact per-channel histograms, episodes pooled as lerobot pools them."""

import numpy as np

from lerobot_export.stats import QUANTILE_KEYS, ImageStats, aggregate, vector_stats


def test_image_stats_equal_numpy_over_every_pixel():
    frames = np.random.default_rng(0).integers(0, 200, (7, 5, 6, 3), dtype=np.uint8)
    stats = ImageStats()
    stats.add(frames[:3])
    stats.add(frames[3:])                       # chunk by chunk, as the exporter feeds it
    result = stats.result()
    pixels = frames.reshape(-1, 3).astype(np.float64)
    for name, expected in (("min", pixels.min(0)), ("max", pixels.max(0)), ("mean", pixels.mean(0)),
                           ("std", pixels.std(0)),
                           ("q01", np.quantile(pixels, 0.01, axis=0, method="inverted_cdf")),
                           ("q99", np.quantile(pixels, 0.99, axis=0, method="inverted_cdf"))):
        assert result[name].shape == (3, 1, 1)
        np.testing.assert_allclose(result[name].ravel() * 255, expected, err_msg=name)
    assert result["count"].tolist() == [7]


def test_pooled_episode_stats_equal_the_stats_of_all_frames():
    rng = np.random.default_rng(1)
    episodes = [rng.normal(size=(n, 4)) for n in (5, 9, 2)]
    pooled = aggregate([{"x": vector_stats(e)} for e in episodes])["x"]
    everything = np.concatenate(episodes)
    np.testing.assert_allclose(pooled["mean"], everything.mean(0))
    np.testing.assert_allclose(pooled["std"], everything.std(0))
    np.testing.assert_array_equal(pooled["min"], everything.min(0))
    assert pooled["count"].tolist() == [16]
    # quantiles: the envelope of the episodes' exact quantiles
    per_episode = np.stack([np.quantile(e, 0.99, axis=0) for e in episodes])
    np.testing.assert_allclose(pooled["q99"], per_episode.max(0))
    assert set(QUANTILE_KEYS) <= set(pooled)
    flags = vector_stats(np.array([True, False, False, True]))    # a scalar feature keeps shape [1]
    assert flags["mean"].tolist() == [0.5] and flags["q50"].shape == (1,)
