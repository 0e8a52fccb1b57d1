"""Asset checks, one result per setting partition: its replays stay within the drift bound, its episodes
match the HDF5 schema and their frames are valid images, and there is at least one of each. They run in
the job that materializes the partition; the `check_episodes` job runs them again on their own."""

import warnings

import dagster as dg

from b2d_pipeline.partitions import settings_partitions
from b2d_pipeline.resources import EpisodeStore
from b2d_pipeline.settings import FactorySettings
from episodes import schema
from episodes.frame_checks import frame_problems, replay_fidelity
from episodes.manifest import read_manifest
from episodes.validate import validate_episode
from sim.errors import SpecError

# Partitioned checks are marked preview in Dagster 1.13 (tested here: tests/test_pipeline_checks.py).
warnings.filterwarnings("ignore", message="Specifying a partitions_def on an AssetCheckSpec",
                        category=dg.PreviewWarning)


def episode_problems(directories) -> tuple[int, dict[str, list[str]]]:
    """(episodes checked, {file: problems}) over episode folders: the schema, a full decode, the
    manifest's sha256 and dataset digests, and manifest entries whose file is gone."""
    problems: dict[str, list[str]] = {}
    checked = 0
    for directory in directories:
        for path in sorted(directory.glob("episode_*.hdf5")):
            checked += 1
            found = validate_episode(path)
            if found:
                problems[str(path)] = found[:20]
        try:
            listed = read_manifest(directory)
        except SpecError as exc:
            problems[str(directory / schema.MANIFEST_NAME)] = [str(exc)]
            continue
        for name in sorted(listed):
            if not (directory / name).exists():
                problems[str(directory / name)] = [f"<file>: missing (listed in {schema.MANIFEST_NAME})"]
    return checked, problems


def _result(checked: int, problems: dict, what: str, folder, **metadata) -> dg.AssetCheckResult:
    if not checked:
        problems = {str(folder): [f"no {what} in this partition"]}
    return dg.AssetCheckResult(passed=not problems, metadata={
        "checked": checked, "problems": dg.MetadataValue.json(problems), **metadata})


def build(settings: FactorySettings, episodes_asset):
    profile = settings.profile

    @dg.asset_check(asset=episodes_asset, partitions_def=settings_partitions,
                    description="The partition has episodes, and every one validates against the HDF5 schema, "
                                "decodes whole and matches the sha256 and dataset digests of episode_manifest.json.")
    def episodes_match_schema(context: dg.AssetCheckExecutionContext, store: EpisodeStore) -> dg.AssetCheckResult:
        folder = store.episode_dir(profile.content_hash, context.partition_key)
        checked, problems = episode_problems([folder] if folder.is_dir() else [])
        return _result(checked, problems, "episodes", folder)

    @dg.asset_check(asset=episodes_asset, partitions_def=settings_partitions,
                    description="Every camera frame of the partition's episodes is a drawn image: RGB not one "
                                "flat colour, depth finite and non-negative.")
    def episode_frames_are_valid(context: dg.AssetCheckExecutionContext, store: EpisodeStore) -> dg.AssetCheckResult:
        folder = store.episode_dir(profile.content_hash, context.partition_key)
        paths = sorted(folder.glob("episode_*.hdf5")) if folder.is_dir() else []
        problems = {}
        for path in paths:
            try:
                found = frame_problems(path)
            except SpecError as exc:          # unreadable: the schema check names it too
                found = [str(exc)]
            if found:
                problems[str(path)] = found
        return _result(len(paths), problems, "episodes", folder)

    @dg.asset_check(asset="replays", partitions_def=settings_partitions,
                    description="The partition has replays, and no replay's objects drift from the recording "
                                "beyond the replay's drift bound.")
    def replays_within_drift_bound(context: dg.AssetCheckExecutionContext, store: EpisodeStore) -> dg.AssetCheckResult:
        folder = store.replay_dir(context.partition_key)
        paths = sorted(folder.glob("*.replay.h5")) if folder.is_dir() else []
        fidelity, problems = {}, {}
        for path in paths:
            try:
                fidelity[path.name] = found = replay_fidelity(path)
            except (OSError, KeyError, ValueError) as exc:
                problems[str(path)] = [f"attrs/fidelity: unreadable ({type(exc).__name__}: {exc})"]
                continue
            if found["frames_over_bound"]:
                problems[str(path)] = [f"{found['frames_over_bound']} frames drift beyond {found['drift_bound_m']} m "
                                       f"(max {found['max_object_position_drift_m']:.4f} m)"]
        return _result(len(paths), problems, "replays", folder, fidelity=dg.MetadataValue.json(fidelity))

    return [episodes_match_schema, episode_frames_are_valid, replays_within_drift_bound]
