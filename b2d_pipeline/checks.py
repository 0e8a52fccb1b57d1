"""Asset checks: every episode of a partition is intact and matches the HDF5 schema."""


import dagster as dg

from b2d_pipeline.resources import EpisodeStore
from b2d_pipeline.settings import FactorySettings
from episodes import schema
from episodes.manifest import read_manifest
from episodes.validate import validate_episode
from sim.errors import SpecError


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


def build(settings: FactorySettings, episodes_asset):
    profile = settings.profile

    @dg.asset_check(asset=episodes_asset, description="Every episode validates against the HDF5 schema, decodes "
                                                      "whole and matches the sha256 and dataset digests of "
                                                      "episode_manifest.json.")
    def episodes_match_schema(context: dg.AssetCheckExecutionContext, store: EpisodeStore) -> dg.AssetCheckResult:
        root = store.root / "episodes" / profile.content_hash
        checked, problems = episode_problems(sorted(p for p in root.glob("*") if p.is_dir()))
        return dg.AssetCheckResult(passed=not problems, metadata={"checked": checked,
                                                                  "problems": dg.MetadataValue.json(problems)})

    return [episodes_match_schema]
