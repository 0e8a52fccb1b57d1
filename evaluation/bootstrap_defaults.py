"""The bootstrap confidence intervals' defaults (paper appendix "Evaluation Metrics"): resamples, seed and
level. Apart from evaluation/metrics.py so that the CLI's options read them without importing pandas
(every process a `b2d` command spawns imports the CLI again)."""

N_BOOT, SEED, LEVEL = 10_000, 0, 0.95
