"""`b2d bench policy`: training speed, inference latency, closed-loop evaluation throughput and peak memory
of a learned policy, with the privileged scripted baseline's evaluation throughput from the same run as
the reference (the rollouts the pipeline ran before learned policies existed).

Each phase runs in its own spawned process, so its peak resident memory is its own; GL rasterizes on the
calling thread and torch uses one thread, so "per core" is one core.
"""

from __future__ import annotations

import multiprocessing
import os
import resource
import statistics
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"
CHANNEL = "none"


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _make_episodes(work: Path, policy: str, config: str, demos: int, demo_steps: int | None) -> list[str]:
    from episodes.stages import raw_to_episode
    from policies.config import load_policy_config
    from sim.registry import sensor_profile
    from teleop.demos import record_demonstrations

    profile = sensor_profile(load_policy_config(policy, config).observation.sensor_profile)
    results = record_demonstrations(TASK, EMBODIMENT, demos, work / "raw", max_steps=demo_steps)
    return [str(raw_to_episode(r.path, profile, work / "episodes")) for r in results if r.path]


def _train(policy: str, config: str, episodes: list[str], out: str, steps: int) -> dict:
    from policies.config import load_policy_config
    from policies.train import train_policy

    result = train_policy(load_policy_config(policy, config), [Path(p) for p in episodes], Path(out), steps=steps)
    return {"steps": result.steps, "seconds": result.seconds, "steps_per_second": result.steps_per_second,
            "frames": result.frames, "peak_rss_mb": _peak_mb()}


def _evaluate(checkpoint: str | None, episodes: int, max_steps: int | None, queries: int) -> dict:
    import numpy as np

    from policies.closed_loop import run_episode
    from policies.rollouts import rollout_seed
    from sim import physics
    from policies.scripted_baseline import ScriptedBaseline
    from sim.scene.builder import demonstration_scene

    if checkpoint:
        from policies.learned import LearnedPolicy
        policy = LearnedPolicy(checkpoint)
    else:
        policy = ScriptedBaseline()
    walls, timings, steps, queried, successes = [], [], [], [], 0
    for i in range(episodes):
        scene = demonstration_scene(TASK, EMBODIMENT, index=i)
        t0 = time.perf_counter()
        outcome = run_episode(policy, scene, rollout_seed(TASK, CHANNEL, i), max_steps=max_steps)
        walls.append(time.perf_counter() - t0)
        timings.append(outcome.timing.as_dict())
        steps.append(outcome.timing.control_steps)
        queried.append(outcome.timing.queries)
        successes += bool(outcome.record["success"])
    out = {"episodes": episodes, "seconds_per_episode": statistics.mean(walls),
           "episodes_per_hour_per_core": 3600.0 / statistics.mean(walls),
           "control_steps_per_episode": statistics.mean(steps), "queries_per_episode": statistics.mean(queried),
           "successes": successes}
    parts = {k: sum(t[k] for t in timings) for k in ("render", "policy", "physics", "evaluate")}
    total = sum(walls)
    out["share"] = {k: v / total for k, v in parts.items()} | {"other": 1.0 - sum(parts.values()) / total}
    policy_steps = sum(steps) // (physics.CONTROL_HZ // policy.observation_spec.rate_hz)
    out["ms_per_policy_step"] = {k: 1e3 * v / max(1, policy_steps) for k, v in parts.items()}
    # wall time above grows with the machine's load; the rendering thread's CPU time does not
    out["render_cpu_ms_per_policy_step"] = 1e3 * sum(t["render_cpu"] for t in timings) / max(1, policy_steps)
    if checkpoint and queries:
        out["inference_ms_per_query"] = _inference_ms(policy, queries, np)
    out["peak_rss_mb"] = _peak_mb()
    return out


def _inference_ms(policy, queries: int, np) -> dict:
    """`act` on one real observation (rendered from a homed scene), repeated: median and p90 ms."""
    from policies.observe import ObservationSource
    from sim.scene.builder import demonstration_scene
    from teleop.recorder import home

    scene = demonstration_scene(TASK, EMBODIMENT)
    data = home(scene)
    source = ObservationSource(scene, policy.observation_spec)
    try:
        source.capture(data)
        obs = source.observation(scene.task.instruction, 0)
    finally:
        source.close()
    policy.reset(0, scene.task.instruction)
    times = []
    for _ in range(queries):
        t0 = time.perf_counter()
        policy.act(obs)
        times.append(1e3 * (time.perf_counter() - t0))
    return {"median": float(np.median(times)), "p90": float(np.percentile(times, 90))}


def _in_child(fn, *args):
    # a process pool that stops its worker with a sentinel: multiprocessing.Pool's exit sends SIGTERM,
    # which a worker never gets when the caller's parent left SIGTERM ignored (it survives exec)
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        return pool.submit(fn, *args).result()


def run_policy_bench(policy: str = "act", config: str = "tiny", demos: int = 2, train_steps: int = 50,
                     eval_episodes: int = 2, max_steps: int | None = None, queries: int = 50,
                     demo_steps: int | None = None) -> dict:
    """`max_steps` caps the timed episodes (default: the full budget), `demo_steps` the demonstrations."""
    os.environ.setdefault("LP_NUM_THREADS", "0")     # GL on the calling thread: per-core figures
    with tempfile.TemporaryDirectory(prefix="b2d-bench-policy-") as tmp:
        work = Path(tmp)
        t0 = time.perf_counter()
        episodes = _in_child(_make_episodes, work, policy, config, demos, demo_steps)
        data_s = time.perf_counter() - t0
        training = _in_child(_train, policy, config, episodes, str(work / "ckpt"), train_steps)
        learned = _in_child(_evaluate, str(work / "ckpt"), eval_episodes, max_steps, queries)
        baseline = _in_child(_evaluate, None, eval_episodes, max_steps, 0)
    return {
        "policy": policy, "config": config, "setting": f"{TASK}__{EMBODIMENT}", "channel": CHANNEL,
        "data": {"demonstrations": demos, "frames": training["frames"], "seconds": data_s},
        "training": training, "evaluation": learned, "baseline_scripted_operator": baseline,
        "evaluation_vs_baseline": learned["episodes_per_hour_per_core"] / baseline["episodes_per_hour_per_core"],
        "note": "the learned policy is barely trained here, so its episodes run the full budget (1.5x expert); "
                "the baseline succeeds and stops early",
    }
