"""`b2d bench chain`: the main job's wall time through Dagster's multiprocess executor with one and with
two step processes, and what Dagster adds around the work: per run, its wall time against the time its
steps spent computing (from the run's step events), per step the start-up and hand-over cost.

Each configuration runs on a fresh data root and a fresh instance, so both do the same work."""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import dagster as dg

from b2d_pipeline.chain import materialize_chain
from b2d_pipeline.settings import FactorySettings


def _step_seconds(instance: dg.DagsterInstance, run_id: str) -> list[float]:
    """Compute time of each step of a run: STEP_START to STEP_SUCCESS/STEP_FAILURE."""
    started, spans = {}, []
    for record in instance.all_logs(run_id):
        event = record.dagster_event
        if event is None or event.step_key is None:
            continue
        if event.event_type_value == "STEP_START":
            started[event.step_key] = record.timestamp
        elif event.event_type_value in ("STEP_SUCCESS", "STEP_FAILURE") and event.step_key in started:
            spans.append(record.timestamp - started.pop(event.step_key))
    return spans


def _one(setting: str, processes: int, overrides: dict) -> dict:
    with tempfile.TemporaryDirectory(prefix="b2d-chain-bench-") as tmp:
        settings = FactorySettings.from_env(data_root=Path(tmp), **overrides)
        (Path(tmp) / "dagster_home").mkdir()
        with dg.instance_for_test(temp_dir=str(Path(tmp) / "dagster_home")) as instance:
            t0 = time.perf_counter()
            results = materialize_chain(settings, [setting], instance, log=lambda _: None, processes=processes)
            wall = time.perf_counter() - t0
            runs = []
            for result in results:
                run = instance.get_run_by_id(result.run_id)
                stats = instance.get_run_stats(result.run_id)
                steps = _step_seconds(instance, result.run_id)
                runs.append({"job": run.job_name, "partition": run.tags.get("dagster/partition"),
                             "wall_s": round(stats.end_time - stats.start_time, 2) if stats.end_time and stats.start_time else None,
                             "steps": len(steps), "step_compute_s": round(sum(steps), 2),
                             "success": result.success})
    compute = sum(r["step_compute_s"] for r in runs)
    steps = sum(r["steps"] for r in runs)
    return {"processes": processes, "wall_s": round(wall, 1), "success": all(r["success"] for r in runs),
            "step_compute_s": round(compute, 1), "steps": steps,
            # wall time the cores had, minus the steps' compute, per step: process start, imports, IO, events
            "dagster_overhead_s_per_step": round((wall * processes - compute) / max(steps, 1), 2),
            "runs": runs}


def run_chain_bench(setting: str, processes: tuple[int, ...] = (1, 2), **overrides) -> dict:
    os.environ.setdefault("LP_NUM_THREADS", "0")
    rows = [_one(setting, p, overrides) for p in processes]
    base = rows[0]["wall_s"]
    return {"setting": setting, "settings": {k: str(v) for k, v in overrides.items()},
            "configurations": rows,
            "speedup_vs_first": {str(r["processes"]): round(base / r["wall_s"], 2) for r in rows}}
