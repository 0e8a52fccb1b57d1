"""Record demonstrations for a setting: one raw recording per episode, each in its own scene
sample; a failing episode is logged and skipped, never stopping the others.

Operators: ``stream`` (default) plays the person through the live session's stream interface
(keypoints and wrist poses -> sanitizer -> DexPilot + arm IK; ``teleop/scripted_stream.py``);
``scripted`` commands the same plan's joints directly, the baseline it is measured against."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

from episodes.raw import write_raw
from sim.errors import SpecError
from sim.registry import validate_name
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample, demonstration_seed
from sim.tasks import load_task
from teleop.recorder import record_episode
from teleop.scripted_operator import ScriptedOperator
from teleop.scripted_stream import ScriptedStreamOperator

log = logging.getLogger(__name__)
OPERATORS = {"stream": ScriptedStreamOperator, "scripted": ScriptedOperator}
DEFAULT_OPERATOR = "stream"


@dataclass
class RecordedEpisode:
    episode_id: str
    path: Path | None
    success: bool
    steps: int
    error: str | None = None


def raw_filename(episode_id: str) -> str:
    return f"episode_{episode_id}.raw.h5"


def record_demonstrations(task: str, embodiment: str, episodes: int, out_dir: Path,
                          max_steps: int | None = None, first_index: int = 0, progress=None,
                          operator: str = DEFAULT_OPERATOR, allow_draft: bool = False) -> list[RecordedEpisode]:
    """Scripted demonstrations first_index.. of the task on the embodiment, written to ``out_dir``. A draft
    plan (`demo_plan_draft: true`, no stable success yet) is refused unless ``allow_draft`` (the bench)."""
    if operator not in OPERATORS:
        raise ValueError(f"operator: expected one of {list(OPERATORS)}, got {operator!r}")
    validate_name("task", task)
    validate_name("embodiment", embodiment)
    spec = load_task(task)
    if not spec.demo_plan:     # fail once, before any scene is built, rather than record idle episodes
        raise SpecError(spec.source, "demo_plan", "a pick-and-place plan for the scripted operator",
                        "none: this task has no scripted demonstration yet")
    if spec.demo_plan_draft and not allow_draft:    # demonstrations that fail do not belong in the data
        raise SpecError(spec.source, "demo_plan_draft", "a finished plan (a draft runs only in `b2d bench demos "
                        "--setting KEY`)", "true: the plan does not reach stable success yet")
    results = []
    for i in range(first_index, first_index + episodes):
        episode_id = f"{i:04d}"
        seed = demonstration_seed(task, i)
        try:
            scene = build_scene(spec, embodiment, demonstration_sample(spec, seed))
            rec = record_episode(scene, OPERATORS[operator](), episode_id, seed, max_steps=max_steps)
            path = write_raw(Path(out_dir) / raw_filename(episode_id), rec)
            results.append(RecordedEpisode(episode_id, path, rec.success, rec.num_steps))
        except Exception as exc:   # one bad episode never stops the others
            log.exception("episode %s of %s on %s failed", episode_id, task, embodiment)
            results.append(RecordedEpisode(episode_id, None, False, 0, f"{type(exc).__name__}: {exc}"))
        if progress:
            progress(1)
    return results
