"""Seeded bootstrap: the same inputs and seed give the same intervals; the stratified (count-based)
draw has the distribution of resampling the episodes themselves."""

import numpy as np
import pytest

from evaluation.metrics import bootstrap_ci
from result_tables.aggregate import stratified_sr_ci


def test_same_seed_same_interval_other_seed_other_interval():
    n, k = np.array([50.0, 50.0, 30.0]), np.array([9.0, 17.0, 4.0])
    w = np.full(3, 1 / 3)
    a = stratified_sr_ci(n, k, w, 2000, seed=0)
    assert a == stratified_sr_ci(n, k, w, 2000, seed=0)
    assert a != stratified_sr_ci(n, k, w, 2000, seed=1)
    mean = float((k / n) @ w)
    assert a[0] < mean < a[1]


def test_one_cell_matches_resampling_its_episodes():
    episodes = np.array([1.0] * 20 + [0.0] * 30)
    lo, hi = stratified_sr_ci(np.array([50.0]), np.array([20.0]), np.array([1.0]), 10_000, seed=0)
    ref_lo, ref_hi = bootstrap_ci(episodes, 10_000, seed=0)
    assert lo == pytest.approx(ref_lo, abs=0.021) and hi == pytest.approx(ref_hi, abs=0.021)  # one episode = 0.02


def test_certain_cells_have_degenerate_intervals_and_no_cells_none():
    assert stratified_sr_ci(np.array([10.0, 10.0]), np.array([10.0, 0.0]), np.array([0.5, 0.5]), 500, 0) == (0.5, 0.5)
    assert stratified_sr_ci(np.array([]), np.array([]), np.array([]), 500, 0) == (None, None)


def test_output_names_match_the_figures():
    from result_tables.build import FIGURE_NAMES
    from result_tables.plots import FIGURES
    assert tuple(FIGURES) == FIGURE_NAMES
