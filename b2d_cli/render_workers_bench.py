"""`b2d bench replay --workers N`: one episode's render on N workers against one worker, in the same run.

The cores are shared with other processes, so beside wall-clock ratios every figure is also given in
CPU seconds of each process taking part: the writing process and every helper. What a render would
take on N idle cores is its critical path, the busiest process's CPU seconds (the helpers build their
scene while the writer builds its own, then all take frames from one counter). The one- and N-worker
renders alternate, so both see the same load.
"""

from __future__ import annotations

import multiprocessing
import os
import statistics
import threading
import time
from contextlib import closing
from pathlib import Path

from episodes.atomic import file_sha256
from episodes.render_pool import shared_helpers
from episodes.stages import render_to_file
from episodes.workers import die_with_parent, one_core


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
                            "helper_frames": info["helper_frames"],
                            "helper_frames_through_pipe": info["helper_frames_through_pipe"],   # not the ring
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
                 "renderer, passing frames); helper_frames_through_pipe: helpers' frames that found no room in "
                 "their shared-memory ring (or had none) and went through the pipe"),
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
        for way in ways[r % len(ways):] + ways[:r % len(ways)]:
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
    """`b2d replay` of ``files`` recordings (copies of one, under their own names) four ways: one worker;
    ``workers`` sharing each recording's render (render helpers, started as the first replay begins);
    ``workers`` processes replaying whole recordings (episodes/replay_batch.py), with and without a process
    that has none left to take helping render the others' (episodes/render_desk.py). Each way starts with no
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
        if way.startswith("whole_recordings"):
            helping = way == "whole_recordings"
            with closing(replay_recordings(raws, profile, out, workers=workers, shared=shared,
                                           help_others=helping)) as batch:
                done = list(batch)
            if helping:
                helped.append(shared["frames_helped"])
        else:   # each recording in turn: alone, or (the way before) its render shared with helpers
            n = 1 if way == "one_worker" else workers
            done = [result for raw in raws for result in replay_recordings([raw], profile, out, workers=n)]
        close_shared_helpers()       # the helpers' CPU seconds count once they have ended
        wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0 + children_cpu() - child0
        failed = [f"{p}: {e}" for p, e in done if isinstance(e, Exception)]
        if failed:
            raise RuntimeError(f"batch replay ({way}) failed: {failed}")
        return wall, cpu, [file_sha256(e) for _, e in done]

    shared: dict = {}
    helped: list[int] = []      # per run: frames this process rendered for the spawned ones' recordings
    ways = ["one_worker", "render_shared", "whole_recordings_no_help", "whole_recordings"]
    walls: dict[str, list[float]] = {w: [] for w in ways}
    cpus: dict[str, list[float]] = {w: [] for w in ways}
    hashes: dict[str, list[str]] = {}
    for r in range(repeats):
        for way in ways[r % len(ways):] + ways[:r % len(ways)]:
            wall, cpu, hashes[way] = run(way)
            walls[way].append(round(wall, 3))
            cpus[way].append(round(cpu, 3))
    wall = {w: statistics.median(v) for w, v in walls.items()}
    return {
        "files": files, "workers": workers, "repeats": repeats,
        "wall_s_median": wall, "wall_s": walls, "cpu_s": cpus,
        "speedup_vs_one_worker": {w: round(wall["one_worker"] / wall[w], 3) for w in ways[1:]},
        "whole_recordings_vs_render_shared": round(wall["render_shared"] / wall["whole_recordings"], 3),
        "help_vs_no_help": round(wall["whole_recordings_no_help"] / wall["whole_recordings"], 3),
        "whole_recordings_frames_helped": helped,
        "episodes_identical": len({tuple(h) for h in hashes.values()}) == 1,
        "note": ("replay + render + assemble of every recording, from no helper or worker process up; "
                 "render_shared: the recordings in turn, each render shared with helper processes (the only "
                 "way before stop 35); whole_recordings: each of `workers` processes replays whole recordings, and one with none "
                 "left to take helps render the others' (frames_helped: how many frames were rendered so); "
                 "whole_recordings_no_help: the same without that help (the way before stop 38); "
                 "wall clock, so other processes' load counts; cpu_s includes the processes' start-up"),
    }


WAIT_S = 600.0      # a side-by-side process that sends nothing for this long has failed


def side_by_side_figures(replay_path: Path, profile, workers: int, out_dir: Path, repeats: int = 3) -> dict:
    """What the cores allow any split of one render: the same file rendered whole by this process alone,
    against `workers` processes each rendering it whole at the same moment (this one and `workers` - 1
    spawned ones, started and warmed up first). Nothing is shared, so whatever slows them down together
    is the machine's (cores contending for caches and memory, or vCPUs that share a physical core):
    `ceiling_speedup` = `workers` x the time alone over the time together, the best a render split over
    that many processes can reach here. Wall clock, medians over `repeats` alternating rounds."""
    ctx = multiprocessing.get_context("spawn")
    start, results = ctx.Barrier(workers), ctx.Queue()
    others = [ctx.Process(target=_render_when_started, name=f"b2d-side-by-side-{k}", daemon=True,
                          args=(replay_path, profile, out_dir / f"side_{k}.render.h5", start, results, repeats,
                                os.getpid()))
              for k in range(1, workers)]
    for process in others:
        process.start()
    try:
        render_to_file(replay_path, profile, out_dir / "side_0.render.h5", max_frames=8)    # warm, as they are
        for _ in others:
            results.get(timeout=WAIT_S)       # each has imported, started GL and rendered a few frames
        alone, together = [], []
        for r in range(repeats):
            for way in (("alone", "together") if r % 2 == 0 else ("together", "alone")):
                if way == "together":
                    start.wait()
                t0 = time.perf_counter()
                render_to_file(replay_path, profile, out_dir / "side_0.render.h5")
                wall = time.perf_counter() - t0
                if way == "alone":
                    alone.append(round(wall, 3))
                else:
                    together.append(round(max([wall] + [results.get(timeout=WAIT_S) for _ in others]), 3))
    finally:
        start.abort()       # a process still waiting for a round (this one failed) stops waiting
        for process in others:
            process.join(timeout=60)
            if process.is_alive():
                process.kill()
    ratio = statistics.median(together) / statistics.median(alone)
    hashes = {file_sha256(out_dir / f"side_{k}.render.h5") for k in range(workers)}
    return {
        "workers": workers, "repeats": repeats, "wall_s_alone": alone, "wall_s_together": together,
        "render_files_identical": len(hashes) == 1,
        "together_vs_alone": round(ratio, 3), "ceiling_speedup": round(workers / ratio, 3),
        "note": ("the same render file made whole by one process alone, and by `workers` processes at once "
                 "(the slowest of them); nothing passes between them, so ceiling_speedup is the best any split "
                 "of one render over that many processes can reach on these cores"),
    }


def _render_when_started(replay_path: Path, profile, out_path: Path, start, results, rounds: int,
                         parent_pid: int) -> None:
    """A side-by-side process: warm up, then render the whole file once per round as the barrier opens."""
    die_with_parent(parent_pid)
    one_core()
    render_to_file(replay_path, profile, out_path, max_frames=8)
    results.put(0.0)
    for _ in range(rounds):
        try:
            start.wait()
        except threading.BrokenBarrierError:     # the benchmark failed: nothing more to render
            return
        t0 = time.perf_counter()
        render_to_file(replay_path, profile, out_path)
        results.put(time.perf_counter() - t0)
