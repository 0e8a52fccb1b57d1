"""Ops of the graph-backed `<policy>_rollouts` assets: a (setting, channel) cell's closed-loop episodes
split into chunks of `episodes_per_step`, one step per chunk, so that an executor spreads a cell's
rollouts over processes (multiprocess) or machines (Celery, Kubernetes); one step gathers the chunks'
rows in episode order and writes the cell's records file. Episode i's seed and anchor depend on i only
(policies/rollouts.py), so the file is the same however the episodes are chunked.

The chunk steps hand their rows to the gathering step as JSON (b2d_pipeline/json_io.py): evaluator
records are plain JSON-shaped values, and Python floats round-trip through JSON exactly.
"""

# no `from __future__ import annotations`: Dagster reads the ops' config annotation at definition time
from typing import Callable

import dagster as dg

from b2d_pipeline.assets.common import CPU_POOL, data_version
from b2d_pipeline.ops.render_replays import JSON_IO
from b2d_pipeline.resources import EpisodeStore
from policies.records import records_frame, write_records
from policies.rollouts import run_rollouts
from sim.registry import parse_setting_key


def chunks(episodes: int, per_step: int) -> list[tuple[int, int]]:
    """[(first episode, count)] covering 0..episodes-1."""
    return [(first, min(per_step, episodes - first)) for first in range(0, episodes, per_step)]


def build_rollout_graph(name: str, Config: type[dg.Config], make_cell: Callable, provenance: Callable[[dict], dict]):
    """`Config`: the run parameters (b2d_pipeline/run_config.py rollout_config); `make_cell(store,
    setting_key)` -> (policy, anchors) for one cell (called in every chunk step); `provenance(chunk)` ->
    the columns every row of the file carries (result_tables reads them)."""

    @dg.op(name=f"plan_{name}", ins={"upstream": dg.In(dg.Nothing)}, out=dg.DynamicOut(dict, io_manager_key=JSON_IO))
    def plan(config: Config):
        for first, count in chunks(config.episodes, config.episodes_per_step):
            yield dg.DynamicOutput({"first": first, "count": count, "max_steps": config.max_steps},
                                   mapping_key=f"episodes_{first:05d}")

    @dg.op(name=f"run_{name}", out=dg.Out(dict, io_manager_key=JSON_IO), pool=CPU_POOL)
    def run_chunk(context: dg.OpExecutionContext, store: EpisodeStore, chunk: dict) -> dict:
        keys = context.partition_key.keys_by_dimension
        setting = parse_setting_key(keys["setting"])
        policy, anchors = make_cell(store, keys["setting"])
        rows = run_rollouts(policy, setting.task, setting.embodiment, keys["channel"], anchors, chunk["count"],
                            max_steps=chunk["max_steps"], first=chunk["first"])
        return {**chunk, "rows": rows, "policy": policy.name, "anchors": len(anchors)}

    @dg.op(name=f"gather_{name}", out=dg.Out(dict, io_manager_key=JSON_IO))
    def gather(context: dg.OpExecutionContext, store: EpisodeStore, done: list[dict]) -> dg.Output:
        keys = context.partition_key.keys_by_dimension
        done = sorted(done, key=lambda c: c["first"])
        rows = [row for chunk in done for row in chunk["rows"]]
        df = records_frame(rows).assign(**provenance(done[0]))
        out = write_records(df, store.rollout_path(done[0]["policy"], keys["setting"], keys["channel"]))
        described = store.describe([out])
        errors = int((df["termination"] == "error").sum()) if "termination" in df else 0
        return dg.Output(described, data_version=data_version(described), metadata={
            "rollouts": len(df), "successes": int(df["success"].sum()), "errors": errors,
            "anchors": done[0]["anchors"], "steps": len(done), "file": dg.MetadataValue.path(str(out))})

    def rollout_graph(upstream):
        return gather(plan(upstream).map(run_chunk).collect())

    return rollout_graph
