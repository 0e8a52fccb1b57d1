"""Evaluation rollouts of any policy under a generalization channel: one labelled row per episode.

Anchored channels (none, equi_only, inv_only) start from the scene sample of the matched recorded
episode (aligned by episode index); inv_equi samples independently. Each episode rebuilds its scene and
runs in closed loop (`policies/closed_loop.py`): horizon 1.5x the task's expert horizon, reach-and-stop.
A failed episode (the policy raised, or the scene could not be built) stays in the table as an error row,
a failure in every denominator (paper), and the others go on.
"""

from __future__ import annotations

import logging

from policies.closed_loop import IncompatiblePolicy, run_episode
from policies.interface import Policy
from sim.registry import channel, channel_names, names
from sim.scene.builder import build_scene
from sim.scene.sample import SceneSample, channel_sample, task_seed
from sim.tasks import load_task

log = logging.getLogger(__name__)
EVAL_SEED_OFFSET = 50_000_000      # evaluation seeds live in the upper half of the task namespace


def rollout_seed(task: str, channel_name: str, index: int) -> int:
    return task_seed(names("tasks").index(task),
                     EVAL_SEED_OFFSET + channel_names().index(channel_name) * 1_000_000 + index)


def run_rollouts(policy: Policy, task: str, embodiment: str, channel_name: str,
                 anchors: list[tuple[str, SceneSample]], episodes: int, max_steps: int | None = None,
                 progress=None, first: int = 0) -> list[dict]:
    """One row per rollout: the evaluator's episode record plus labels (task, embodiment, policy,
    channel, episode, seed, anchor), for episodes first..first+episodes-1 (an episode's seed and anchor
    depend on its index only, so a cell can be run in chunks). `progress(1)` after each episode."""
    spec, chan = load_task(task), channel(channel_name)
    operator = getattr(policy, "operator_name", None)
    rows = []
    for i in range(first, first + episodes):
        anchor_id, anchor = anchors[i % len(anchors)] if anchors else (None, None)
        seed = rollout_seed(task, channel_name, i)
        labels = {"task": task, "embodiment": embodiment, "policy": policy.name, "operator": operator,
                  "channel": channel_name, "episode": i, "seed": seed, "anchor": anchor_id if chan.anchored else None}
        try:
            sample = channel_sample(spec, chan, seed, anchor, anchor_id)
            outcome = run_episode(policy, build_scene(spec, embodiment, sample), seed, f"{i:04d}",
                                  max_steps=max_steps)
            rows.append({**outcome.record, **labels, "scene_sample": sample.to_json()})
        except IncompatiblePolicy:
            raise                  # every episode would fail alike: refuse the evaluation as a whole
        except Exception as exc:   # a failed rollout stays in the denominator (paper)
            log.exception("rollout %d of %s on %s/%s failed", i, policy.name, task, channel_name)
            rows.append({**labels, "success": False, "termination": "error", "error": f"{type(exc).__name__}: {exc}"})
        if progress:
            progress(1)
    return rows
