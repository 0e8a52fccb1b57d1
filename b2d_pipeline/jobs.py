"""The project's jobs, each an asset selection: what a person or a schedule launches by name."""

from __future__ import annotations

import dagster as dg

# setting_specs first: each production run observes its catalog files, so an edit shows as stale
PRODUCTION = ["setting_specs", "raw_recordings", "replays", "renders", "episodes"]
ROLLOUTS = dg.AssetSelection.groups("evaluation") - dg.AssetSelection.assets("evaluation_table")

production_job = dg.define_asset_job(
    "produce_episodes", selection=PRODUCTION,
    description="Record, replay, render and write the HDF5 episodes of a setting.")

training_job = dg.define_asset_job(
    "train_policies", selection=dg.AssetSelection.groups("training"),
    description="Render the policies' inputs from stored replays and train each policy's checkpoint.")

produce_and_train_job = dg.define_asset_job(
    "produce_and_train", selection=dg.AssetSelection.assets(*PRODUCTION) | dg.AssetSelection.groups("training"),
    description="A setting from demonstrations to trained checkpoints (the two branches run side by side).")

evaluation_job = dg.define_asset_job(
    "evaluate_policies", selection=ROLLOUTS,
    description="Every policy's closed-loop rollouts of one (setting, channel), side by side.")

table_job = dg.define_asset_job(
    "build_evaluation_table", selection=["evaluation_table"],
    description="The result table over every rollout file.")

rerender_job = dg.define_asset_job(
    "rerender_episodes", selection=["renders", "episodes"],
    description="Re-render stored replays under the active sensor profile (no re-simulation).")

teleop_job = dg.define_asset_job(
    "ingest_teleop", selection=["teleop_episodes"],
    description="A live teleoperation recording to its HDF5 episode (one dynamic partition per recording).")

# With the checks alone the job would have no partitions (Dagster 1.13 takes a job's partitions from its
# assets and ignores a job-level partitions_def when there are none); setting_specs, a cheap observation
# of the setting's catalog files, gives it the setting partitions.
check_job = dg.define_asset_job(
    "check_episodes",
    selection=dg.AssetSelection.checks_for_assets("replays", "episodes") | dg.AssetSelection.assets("setting_specs"),
    description="Run a setting's checks again (drift bound, HDF5 schema, frame validity) without re-materializing.")

ALL = [production_job, training_job, produce_and_train_job, evaluation_job, table_job, rerender_job, teleop_job, check_job]
