"""Dagster definitions of the b2d data factory (assets, partitions, schedules, checks)."""
