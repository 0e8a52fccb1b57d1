"""Ops of the graph-backed `renders` asset: one step per stored replay, so that an executor spreads a
setting's renders over processes (multiprocess) or machines (Celery, Kubernetes), then one step that
gathers them. A replay that fails to render is reported by the gathering step after every other replay
is written, as everywhere in the factory."""


import warnings
from pathlib import Path

import dagster as dg

from b2d_pipeline.assets.common import CPU_POOL, data_version, fail_if_errors, require_inputs
from b2d_pipeline.resources import EpisodeStore
from episodes.stages import render_to_file
from sim.registry import SensorProfile

JSON_IO = "json_io"
# an op's Output carrying the asset's data version is marked beta in Dagster 1.13; it is how a graph asset sets one
warnings.filterwarnings("ignore", message=".*`data_version` of initializer `Output", category=dg.BetaWarning)


def mapping_key(file_name: str) -> str:
    """Dagster mapping keys allow letters, digits and underscores only."""
    return "".join(c if c.isalnum() else "_" for c in file_name.removesuffix(".replay.h5"))


def build_render_graph(profile: SensorProfile, render_workers: int):
    @dg.op(ins={"replays": dg.In(dg.Nothing)}, out=dg.DynamicOut(str, io_manager_key=JSON_IO))
    def list_replays(context: dg.OpExecutionContext, store: EpisodeStore):
        folder = store.replay_dir(context.partition_key)
        for replay in require_inputs(sorted(folder.glob("*.replay.h5")), folder, "*.replay.h5", "replays"):
            yield dg.DynamicOutput(str(replay), mapping_key=mapping_key(replay.name))

    @dg.op(out=dg.Out(dict, io_manager_key=JSON_IO), pool=CPU_POOL)
    def render_replay(context: dg.OpExecutionContext, store: EpisodeStore, replay: str) -> dict:
        replay_path = Path(replay)
        out = (store.render_dir(profile.content_hash, context.partition_key)
               / replay_path.name.replace(".replay.h5", ".render.h5"))
        try:
            info = render_to_file(replay_path, profile, out, workers=render_workers)
        except Exception as exc:      # reported by gather_renders, after the other replays are written
            context.log.error(f"{replay_path}: {exc}")
            return {"replay": replay_path.name, "error": str(exc)}
        return {"replay": replay_path.name, "path": str(out), "frames": info["frames"]}

    @dg.op(out=dg.Out(dict, io_manager_key=JSON_IO))
    def gather_renders(store: EpisodeStore, rendered: list[dict]) -> dg.Output:
        fail_if_errors({r["replay"]: r["error"] for r in rendered if "error" in r},
                       sum("path" in r for r in rendered))
        paths = sorted(Path(r["path"]) for r in rendered)
        described = store.describe(paths)
        return dg.Output(
            described,
            metadata={"profile": profile.name, "profile_hash": profile.content_hash,
                      "frames": sum(r["frames"] for r in rendered), "tactile": profile.tactile_enabled,
                      "files": dg.MetadataValue.json(described)},
            data_version=data_version(described, profile.content_hash))

    def render_graph(replays):
        return gather_renders(list_replays(replays).map(render_replay).collect())

    return render_graph
