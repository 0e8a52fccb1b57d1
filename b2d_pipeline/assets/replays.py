"""Deterministic replays of each raw recording (re-simulated states, fidelity, evaluator traces)."""


import dagster as dg

from b2d_pipeline.assets.common import CPU_POOL, data_version, fail_if_errors, require_inputs
from b2d_pipeline.partitions import settings_partitions
from b2d_pipeline.resources import EpisodeStore
from episodes.stages import replay_to_file


def build():
    # 2: replays also store distractor states and articulated-object joint states.
    @dg.asset(partitions_def=settings_partitions, group_name="replays", pool=CPU_POOL, code_version="2", deps=["raw_recordings"],
              description="Seeded re-simulation of every raw recording; profile-independent.")
    def replays(context: dg.AssetExecutionContext, store: EpisodeStore) -> dg.MaterializeResult:
        key = context.partition_key
        paths, errors, fidelity = [], {}, {}
        raws = require_inputs(sorted(store.raw_dir(key).glob("*.raw.h5")), store.raw_dir(key), "*.raw.h5", "raw_recordings")
        for raw in raws:
            out = store.replay_dir(key) / raw.name.replace(".raw.h5", ".replay.h5")
            try:
                info = replay_to_file(raw, out)
                paths.append(out)
                fidelity[info["episode_id"]] = info["fidelity"]
            except Exception as exc:   # one bad recording never stops the others
                context.log.error(f"{raw}: {exc}")
                errors[raw.name] = str(exc)
        fail_if_errors(errors, len(paths))
        described = store.describe(paths)
        return dg.MaterializeResult(
            metadata={"episodes": len(paths), "fidelity": dg.MetadataValue.json(fidelity),
                      "files": dg.MetadataValue.json(described)},
            data_version=data_version(described))

    return replays
