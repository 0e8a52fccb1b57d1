"""Asset checks: every episode of a partition matches the HDF5 schema."""


import dagster as dg

from b2d_pipeline.resources import EpisodeStore
from b2d_pipeline.settings import FactorySettings
from episodes.validate import validate_episode


def build(settings: FactorySettings, episodes_asset):
    profile = settings.profile

    @dg.asset_check(asset=episodes_asset, description="Every episode validates against the HDF5 schema.")
    def episodes_match_schema(context: dg.AssetCheckExecutionContext, store: EpisodeStore) -> dg.AssetCheckResult:
        problems = {}
        checked = 0
        for path in sorted((store.root / "episodes" / profile.content_hash).glob("*/episode_*.hdf5")):
            checked += 1
            found = validate_episode(path)
            if found:
                problems[str(path)] = found[:20]
        return dg.AssetCheckResult(passed=not problems, metadata={"checked": checked,
                                                                  "problems": dg.MetadataValue.json(problems)})

    return [episodes_match_schema]
