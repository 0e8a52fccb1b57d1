"""Benchmark of the scale-out path on this host: how long Debian's PostgreSQL and redis-server take to start
(through deploy/*.sh), how long two Celery workers take to answer, and the wall time of one partition of the
probe graph (b2d_pipeline/scale_out/probe.py: 4 steps of 0.3 s, two of them side by side) through the
celery executor against the in-process and multiprocess executors, all on the same Postgres instance.
With --renders, also a real partition: one setting's `renders` (one render_replay step per replay, the
replays recorded first with --max-steps control steps each) in process against two Celery workers.

    .venv/bin/python deploy/bench_scale_out.py [--repeats 3] [--renders --replays 2 --max-steps 60]

Everything lives in a temporary folder on free ports and is stopped and removed at the end."""

from __future__ import annotations

import argparse
import os
import shutil
import socket
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import dagster as dg

from b2d_pipeline.scale_out import write_postgres_instance_yaml
from b2d_pipeline.scale_out.local_workers import LocalWorkers
from b2d_pipeline.scale_out.probe import STEP_SECONDS, celery_probe_job, in_process_probe_job, multiprocess_probe_job

DEPLOY = Path(__file__).resolve().parent
JOBS = {"in_process": in_process_probe_job, "multiprocess": multiprocess_probe_job, "celery": celery_probe_job}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def timed_script(script: str, action: str, env: dict) -> float:
    started = time.perf_counter()
    subprocess.run([str(DEPLOY / script), action], env=env, check=True, capture_output=True)
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--renders", action="store_true", help="also time a real partition of `renders`")
    parser.add_argument("--replays", type=int, default=2, help="replays in that partition (one step each)")
    parser.add_argument("--max-steps", type=int, default=60, help="control steps per recorded demonstration")
    parser.add_argument("--profile", default="policy_tiny", help="sensor profile of the renders")
    args = parser.parse_args()
    root = Path(tempfile.mkdtemp(prefix="b2d-bench-", dir="/tmp"))
    root.chmod(0o755)                  # as root, postgres runs as user postgres and must reach its folder
    env = {**os.environ, "B2D_SERVICES_DIR": str(root), "B2D_PG_PORT": str(free_port()),
           "B2D_REDIS_PORT": str(free_port())}
    figures = {}
    try:
        figures["postgres first start (initdb + start)"] = timed_script("postgres.sh", "start", env)
        timed_script("postgres.sh", "stop", env)
        figures["postgres start (existing data)"] = timed_script("postgres.sh", "start", env)
        figures["redis start"] = timed_script("redis.sh", "start", env)
        url = subprocess.run([str(DEPLOY / "postgres.sh"), "url"], env=env, check=True, capture_output=True,
                             text=True).stdout.strip()
        redis = subprocess.run([str(DEPLOY / "redis.sh"), "url"], env=env, check=True, capture_output=True,
                               text=True).stdout.strip()
        home = root / "dagster_home"
        write_postgres_instance_yaml(home, url)
        started = time.perf_counter()
        dg.DagsterInstance.from_config(str(home)).dispose()
        figures["dagster schema on a new database"] = time.perf_counter() - started
        os.environ.update(DAGSTER_HOME=str(home), B2D_CELERY_BROKER=f"{redis}/0", B2D_CELERY_BACKEND=f"{redis}/1")
        preload = ("b2d_pipeline.scale_out.probe",)
        if args.renders:      # the workers rebuild the factory's definitions from these settings
            os.environ.update(B2D_DATA_ROOT=str(root / "data"), B2D_PROFILE=args.profile,
                              MUJOCO_GL=os.environ.get("MUJOCO_GL") or "egl")
            preload += ("b2d_pipeline.chain",)
        started = time.perf_counter()
        with LocalWorkers(["w1", "w2"], dict(os.environ), root, preload=preload) as workers:
            workers.wait_ready(f"{redis}/0", timeout=300)
            figures["two celery workers ready"] = time.perf_counter() - started
            for name, _ in figures.items():
                print(f"{name:42s} {figures[name]:6.2f} s")
            walls = run_probe(home, args.repeats)
            if args.renders:
                render_walls = run_renders(home, root / "data", args)
    finally:
        for script in ("redis.sh", "postgres.sh"):
            subprocess.run([str(DEPLOY / script), "stop"], env=env, capture_output=True)
        shutil.rmtree(root, ignore_errors=True)
    print(f"\nprobe partition (4 steps x {STEP_SECONDS} s; critical path {3 * STEP_SECONDS:.1f} s), "
          f"{args.repeats} runs each, instance on Postgres:")
    base = statistics.median(walls["in_process"])
    for name, runs in walls.items():
        median = statistics.median(runs)
        print(f"  {name:13s} median {median:6.2f} s  ({' '.join(f'{w:.2f}' for w in runs)})  "
              f"x{median / base:.2f} of in_process")
    if args.renders:
        print(f"\nrenders of one setting ({args.replays} replays of {args.max_steps} control steps, profile "
              f"{args.profile}), {args.repeats} runs each, instance on Postgres:")
        base = statistics.median(w for w, _ in render_walls["in_process"])
        for name, runs in render_walls.items():
            median = statistics.median(w for w, _ in runs)
            print(f"  {name:13s} median {median:6.2f} s  ({' '.join(f'{w:.2f} (load {l:.1f})' for w, l in runs)})  "
                  f"x{median / base:.2f} of in_process")


def run_renders(home: Path, data_root: Path, args) -> dict[str, list[tuple[float, float]]]:
    """(wall seconds, 1-minute load average at the end) per run of the partition, in process and on the workers."""
    import sys

    from b2d_pipeline.chain import reconstructable_job
    from b2d_pipeline.settings import FactorySettings
    from b2d_pipeline.resources import EpisodeStore
    from episodes.stages import replay_to_file
    from teleop.demos import record_demonstrations

    setting = "citrus_plate_loading__ur5_rh5dg2"
    task, embodiment = setting.split("__")
    recorded = record_demonstrations(task, embodiment, args.replays, data_root / "recorded", max_steps=args.max_steps)
    folder = EpisodeStore(data_root=str(data_root)).replay_dir(setting)
    folder.mkdir(parents=True, exist_ok=True)
    for r in recorded:
        replay_to_file(r.path, folder / r.path.name.replace(".raw.h5", ".replay.h5"))
    walls = {"in_process": [], "celery": []}
    quiet = {"loggers": {"console": {"config": {"log_level": "ERROR"}}}}
    with dg.DagsterInstance.from_config(str(home)) as instance:
        for _ in range(args.repeats):
            for name in walls:                 # interleaved, as above
                os.environ["B2D_EXECUTOR"] = name
                # the settings in the job's pointer: Dagster keeps the last job loaded per pointer, so one
                # pointer for both executors would run the first one's job every time
                job = reconstructable_job("produce_and_train", FactorySettings.from_env())
                started = time.perf_counter()
                result = dg.execute_job(job, instance, run_config=quiet,
                                        asset_selection=[dg.AssetKey("renders")], tags={"dagster/partition": setting})
                walls[name].append((time.perf_counter() - started, os.getloadavg()[0]))
                assert result.success, name
                print(f"  renders {name}: {walls[name][-1][0]:.2f} s", file=sys.stderr)
    return walls


def run_probe(home: Path, repeats: int) -> dict[str, list[float]]:
    walls = {name: [] for name in JOBS}
    with dg.DagsterInstance.from_config(str(home)) as instance:
        for i in range(repeats):
            for name, job in JOBS.items():     # interleaved, so load on the shared machine hits all alike
                started = time.perf_counter()
                result = dg.execute_job(dg.reconstructable(job), instance, tags={"dagster/partition": f"p{i % 2}"},
                                        run_config={"loggers": {"console": {"config": {"log_level": "ERROR"}}}})
                walls[name].append(time.perf_counter() - started)
                assert result.success, name
    return walls


if __name__ == "__main__":
    main()
