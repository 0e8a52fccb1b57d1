"""`b2d bench replay --workers N`: one episode's render on N workers against one worker, in the same run.

The cores are shared with other processes, so beside wall-clock ratios every figure is also given in
CPU seconds of each process taking part: the writing process and every helper. What a render would
take on N idle cores is its critical path, the busiest process's CPU seconds (the helpers build their
scene while the writer builds its own, then all take frames from one counter). The one- and N-worker
renders alternate, so both see the same load.
"""

from __future__ import annotations

import os
import statistics
import time
from pathlib import Path

from episodes.atomic import file_sha256
from episodes.render_pool import shared_helpers
from episodes.stages import render_to_file


def parallel_render_figures(replay_path: Path, profile, workers: int, out_dir: Path, repeats: int = 3) -> dict:
    """Start the helpers (once per process, timed), then `repeats` interleaved pairs of one-worker and
    `workers`-worker renders of the same replay; medians, every run, and whether the files are the same."""
    t0, cpu0 = time.perf_counter(), time.process_time()
    helpers = shared_helpers(workers - 1)
    start_wall, start_parent_cpu = time.perf_counter() - t0, time.process_time() - cpu0
    runs: dict[int, list[dict]] = {1: [], workers: []}
    for r in range(repeats):
        for n in ((1, workers) if r % 2 == 0 else (workers, 1)):      # alternate which goes first
            load = os.getloadavg()[0]
            t0, cpu0 = time.perf_counter(), time.process_time()
            info = render_to_file(replay_path, profile, out_dir / f"w{n}.render.h5", workers=n)
            wall, own_cpu = time.perf_counter() - t0, time.process_time() - cpu0
            helper_cpu = info["helper_cpu_s"]
            runs[n].append({"wall_s": round(wall, 3), "writer_cpu_s": round(own_cpu, 3),
                            "helpers_cpu_s": round(helper_cpu, 3), "cpu_s": round(own_cpu + helper_cpu, 3),
                            "setup_cpu_s": round(info["setup_cpu_s"], 3),     # every process's, once per file
                            "workers": info["workers"], "load_average_1min": round(load, 2),
                            # on idle cores the busiest process sets the wall time
                            "critical_path_cpu_s": round(max(own_cpu, helper_cpu / max(1, info["workers"] - 1)), 3)})
    identical = file_sha256(out_dir / "w1.render.h5") == file_sha256(out_dir / f"w{workers}.render.h5")

    def median(n: int, key: str) -> float:
        return statistics.median(run[key] for run in runs[n])

    one_cpu, many_cpu = median(1, "cpu_s"), median(workers, "cpu_s")
    return {
        "workers": workers, "frames": info["frames"], "repeats": repeats,
        "speedup_vs_one_worker": round(median(1, "wall_s") / median(workers, "wall_s"), 3),
        "speedup_on_idle_cores_from_cpu": round(one_cpu / median(workers, "critical_path_cpu_s"), 3),
        "speedup_bound_from_cpu": round(workers * one_cpu / max(many_cpu, 1e-9), 3),
        "render_cpu_s_one_worker": one_cpu, "render_cpu_s": many_cpu,
        "sharing_cpu_s": round(many_cpu - one_cpu, 3),
        "render_file_identical_to_one_worker": identical,
        "join_s": 0.0,
        "helpers_start_once": {"wall_s": round(start_wall, 3), "writer_cpu_s": round(start_parent_cpu, 3),
                               "cpu_s_per_helper": {str(k): round(v, 3) for k, v in helpers.startup_cpu_s.items()}},
        "runs": {str(n): r for n, r in runs.items()},
        "note": ("one worker = the render in this process alone; N workers = this process (renders, writes every "
                 "frame in order) and N-1 helper processes kept across calls, all taking frames from one counter; "
                 "helpers_start_once = spawning them (interpreter, imports, GL), paid once per process, not per "
                 "render; nothing is joined (join_s 0): the render file is written once, byte-identical to one "
                 "worker's. speedup_vs_one_worker: wall clock, medians over interleaved repeats (counts other "
                 "processes' load); speedup_on_idle_cores_from_cpu: one worker's CPU seconds over the busiest "
                 "process's CPU seconds (the wall time on idle cores); speedup_bound_from_cpu: N x one worker's CPU "
                 "over all processes' CPU; sharing_cpu_s: the CPU seconds sharing adds (each helper's scene and "
                 "renderer, passing frames)"),
    }


def cold_start_figures(raw_path: Path, profile, workers: int, out_dir: Path, repeats: int = 3) -> dict:
    """One recording replayed and rendered in a process whose helpers have not started, as one
    `b2d replay RAW --workers N` or one executor step runs: one worker, against N workers two ways:
    waiting for the helpers to start before rendering (the code before stop 34) and starting them as
    the physics replay begins, the render taking them on once they are up (now). Wall-clock medians
    over `repeats` rounds, each round in a rotated order."""
    from episodes.render_pool import close_shared_helpers
    from episodes.stages import replay_to_file, start_render_helpers

    def run(way: str) -> Path:
        replay, render = out_dir / f"cold_{way}.replay.h5", out_dir / f"cold_{way}.render.h5"
        if way == "helpers_start_during_replay":
            start_render_helpers(workers - 1, raw_path)
        replay_to_file(raw_path, replay)
        if way == "helpers_waited_for":
            shared_helpers(workers - 1)
        render_to_file(replay, profile, render, workers=1 if way == "one_worker" else workers)
        return render

    ways = ["one_worker", "helpers_waited_for", "helpers_start_during_replay"]
    walls: dict[str, list[float]] = {w: [] for w in ways}
    files: dict[str, str] = {}
    for r in range(repeats):
        for way in ways[r % 3:] + ways[:r % 3]:
            close_shared_helpers()
            t0 = time.perf_counter()
            files[way] = file_sha256(run(way))
            walls[way].append(round(time.perf_counter() - t0, 3))
    close_shared_helpers()
    wall = {w: statistics.median(v) for w, v in walls.items()}
    return {
        "workers": workers, "repeats": repeats, "wall_s_median": wall, "wall_s": walls,
        "speedup_vs_one_worker": {w: round(wall["one_worker"] / wall[w], 3) for w in ways[1:]},
        "now_vs_before": round(wall["helpers_waited_for"] / wall["helpers_start_during_replay"], 3),
        "render_files_identical": len(set(files.values())) == 1,
        "note": ("replay + render of one recording in a process without helpers (each run closes them first): "
                 "what `b2d replay RAW --workers N` and an executor's render step pay; wall clock, so other "
                 "processes' load counts"),
    }


def batch_figures(raw_path: Path, profile, workers: int, out_dir: Path, files: int = 6, repeats: int = 2) -> dict:
    """`b2d replay` of ``files`` recordings (copies of one, under their own names) three ways: one worker;
    ``workers`` sharing each recording's render (render helpers, started as the first replay begins);
    ``workers`` processes replaying whole recordings (episodes/replay_batch.py). Each way starts with no
    helper or worker process up, as a fresh `b2d replay` does. Wall clock (medians over ``repeats``
    rounds in rotated order) and every process's CPU seconds (this one's and its children's)."""
    import resource
    import shutil

    from episodes.render_pool import close_shared_helpers
    from episodes.replay_batch import replay_recordings

    raws = []
    for i in range(files):
        raws.append(out_dir / "batch_raw" / f"episode_{i:04d}.raw.h5")
        raws[-1].parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(raw_path, raws[-1])

    def children_cpu() -> float:
        usage = resource.getrusage(resource.RUSAGE_CHILDREN)
        return usage.ru_utime + usage.ru_stime

    def run(way: str) -> tuple[float, float, list[str]]:
        out = out_dir / f"batch_{way}"
        shutil.rmtree(out, ignore_errors=True)
        close_shared_helpers()
        t0, cpu0, child0 = time.perf_counter(), time.process_time(), children_cpu()
        if way == "whole_recordings":
            done = list(replay_recordings(raws, profile, out, workers=workers))
        else:   # each recording in turn: alone, or (the way before) its render shared with helpers
            n = 1 if way == "one_worker" else workers
            done = [result for raw in raws for result in replay_recordings([raw], profile, out, workers=n)]
        close_shared_helpers()       # the helpers' CPU seconds count once they have ended
        wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0 + children_cpu() - child0
        failed = [f"{p}: {e}" for p, e in done if isinstance(e, Exception)]
        if failed:
            raise RuntimeError(f"batch replay ({way}) failed: {failed}")
        return wall, cpu, [file_sha256(e) for _, e in done]

    ways = ["one_worker", "render_shared", "whole_recordings"]
    walls: dict[str, list[float]] = {w: [] for w in ways}
    cpus: dict[str, list[float]] = {w: [] for w in ways}
    hashes: dict[str, list[str]] = {}
    for r in range(repeats):
        for way in ways[r % 3:] + ways[:r % 3]:
            wall, cpu, hashes[way] = run(way)
            walls[way].append(round(wall, 3))
            cpus[way].append(round(cpu, 3))
    wall = {w: statistics.median(v) for w, v in walls.items()}
    return {
        "files": files, "workers": workers, "repeats": repeats,
        "wall_s_median": wall, "wall_s": walls, "cpu_s": cpus,
        "speedup_vs_one_worker": {w: round(wall["one_worker"] / wall[w], 3) for w in ways[1:]},
        "whole_recordings_vs_render_shared": round(wall["render_shared"] / wall["whole_recordings"], 3),
        "episodes_identical": len({tuple(h) for h in hashes.values()}) == 1,
        "note": ("replay + render + assemble of every recording, from no helper or worker process up; "
                 "render_shared: the recordings in turn, each render shared with helper processes (the only "
                 "way before stop 35); whole_recordings: each of `workers` processes replays whole recordings; "
                 "wall clock, so other processes' load counts; cpu_s includes the processes' start-up"),
    }
