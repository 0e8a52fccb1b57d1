"""Evaluation rollouts of a policy under a generalization channel.

Anchored channels (none, equi_only, inv_only) start from the scene sample of the matched recorded
episode (aligned by episode index); inv_equi samples independently. The horizon is 1.5x the task's
expert horizon (paper), with reach-and-stop termination. The scripted operator rolls out through
the same stream interface as the demonstrations (``teleop/demos.py`` DEFAULT_OPERATOR), so its row
in the result table measures the operator whose demonstrations the policies learn from.
"""

from __future__ import annotations

import logging

from sim.registry import channel, channel_names, names
from sim.scene.builder import build_scene
from sim.scene.sample import SceneSample, channel_sample, task_seed
from sim.tasks import load_task
from teleop.recorder import record_episode
from teleop.demos import DEFAULT_OPERATOR, OPERATORS

log = logging.getLogger(__name__)
EVAL_SEED_OFFSET = 50_000_000      # evaluation seeds live in the upper half of the task namespace


def rollout_seed(task: str, channel_name: str, index: int) -> int:
    return task_seed(names("tasks").index(task),
                     EVAL_SEED_OFFSET + channel_names().index(channel_name) * 1_000_000 + index)


def run_rollouts(task: str, embodiment: str, channel_name: str, anchors: list[tuple[str, SceneSample]],
                 episodes: int, max_steps: int | None = None, policy: str = "scripted_operator",
                 operator: str = DEFAULT_OPERATOR) -> list[dict]:
    """One row per rollout: the evaluator's episode record plus labels. Errors count as failures.
    ``operator``: how the scripted operator drives the robot (``teleop/demos.py`` OPERATORS)."""
    if operator not in OPERATORS:
        raise ValueError(f"operator: expected one of {list(OPERATORS)}, got {operator!r}")
    spec, chan = load_task(task), channel(channel_name)
    rows = []
    for i in range(episodes):
        anchor_id, anchor = anchors[i % len(anchors)] if anchors else (None, None)
        seed = rollout_seed(task, channel_name, i)
        labels = {"task": task, "embodiment": embodiment, "policy": policy, "operator": operator, "channel": channel_name,
                  "episode": i, "seed": seed, "anchor": anchor_id if chan.anchored else None}
        try:
            sample = channel_sample(spec, chan, seed, anchor, anchor_id)
            rec = record_episode(build_scene(spec, embodiment, sample), OPERATORS[operator](), f"{i:04d}", seed,
                                 max_steps=max_steps)    # the recorder stops at the 1.5x expert horizon
            rows.append({**rec.extra["episode_record"], **labels, "scene_sample": sample.to_json()})
        except Exception as exc:   # a failed rollout stays in the denominator (paper)
            log.exception("rollout %d of %s/%s failed", i, task, channel_name)
            rows.append({**labels, "success": False, "termination": "error", "error": str(exc)})
    return rows
