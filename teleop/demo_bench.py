"""`b2d bench demos`: stable-success count of the scripted operator per paper setting, through the
stream interface (default) or the direct joint path (``operator="scripted"``), with the time per
recorded control step (operator + physics + recorder).

Every one of the paper's 26 settings is listed; a setting whose task has no `demo_plan` yet is
reported as such (0 successes) rather than left out, so the table shows how far the issue's goal
("stable success on at least half of the 26 paper settings") is.

With ``--embodiment all|NAME[,NAME]`` it runs each chosen task's plan on those embodiments instead
(teleop/cross_embodiment.py): a task x embodiment table of successes.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from episodes.workers import map_in_processes
from sim.registry import Setting, paper_settings, parse_setting_key
from sim.tasks import is_recordable, load_task
from teleop.cross_embodiment import markdown_table, parse_embodiments, parse_tasks, run_cross_embodiment_bench
from teleop.demos import DEFAULT_OPERATOR, record_demonstrations


def record_one(task: str, embodiment: str, index: int, operator: str) -> dict:
    """Demonstration seed ``index`` recorded in a temporary folder: its success, steps, error and seconds."""
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        (result,) = record_demonstrations(task, embodiment, 1, Path(tmp), first_index=index, operator=operator,
                                          allow_draft=True)
    return {"success": result.success, "steps": result.steps, "error": result.error,
            "seconds": time.perf_counter() - t0}


def settings_to_run(only: list[str] | None = None) -> tuple[list[Setting], list[Setting]]:
    """(the paper settings listed, those recorded): every recordable setting, or only the keys named; a
    draft plan (no stable success yet) runs only when its setting is named."""
    for key in only or ():
        parse_setting_key(key)      # an unknown task or embodiment fails here, naming the valid ones
    chosen = [s for s in paper_settings() if not only or s.key in only]
    return chosen, [s for s in chosen if is_recordable(s) or (only and s.available and load_task(s.task).demo_plan)]


def not_run(setting: Setting) -> str:
    """Why the bench lists ``setting`` without recording it: no plan, or a draft not named."""
    if load_task(setting.task).demo_plan_draft:
        return "draft demo_plan (runs when its setting is named)"
    return "no demo_plan" if setting.available else "not available"


def run_demo_bench(episodes: int = 4, only: list[str] | None = None, operator: str = DEFAULT_OPERATOR,
                   processes: int = 1) -> dict:
    """Seeds 0..episodes-1 of every chosen paper setting with a plan, recorded in ``processes`` processes
    (the same episodes whatever the number: each seed is its own scene and operator)."""
    chosen, to_record = settings_to_run(only)
    units = [(s.task, s.embodiment, i, operator) for s in to_record for i in range(episodes)]
    t0 = time.perf_counter()
    results = iter(map_in_processes(record_one, units, processes))
    by_setting = {s.key: [next(results) for _ in range(episodes)] for s in to_record}
    wall = time.perf_counter() - t0
    rows, succeeded = [], 0
    for setting in chosen:
        row = {"setting": setting.key, "episodes": episodes}
        if setting.key not in by_setting:
            rows.append({**row, "successes": 0, "status": not_run(setting)})
            continue
        done = by_setting[setting.key]
        seconds = sum(r["seconds"] for r in done)       # the setting's work, whichever process did it
        steps = sum(r["steps"] for r in done)
        wins = sum(r["success"] for r in done)
        errors = [r["error"] for r in done if r["error"]]
        succeeded += wins > episodes / 2
        rows.append({**row, "successes": wins, "mean_steps": round(steps / episodes, 1),
                     "seconds": round(seconds, 2), "ms_per_step": round(1e3 * seconds / max(steps, 1), 2),
                     "status": f"{len(errors)} errors: {errors[0]}" if errors else "ok",
                     **({"draft_plan": True} if load_task(setting.task).demo_plan_draft else {})})
    return {"settings": rows, "settings_with_majority_success": succeeded, "settings_listed": len(rows),
            "operator": operator, "processes": processes, "wall_seconds": round(wall, 2),
            "note": f"scripted operator ({operator}), demonstration seeds 0..episodes-1 of each setting; success = the "
                    "evaluator's stable success (reach-and-stop); a setting's seconds are its episodes' own, "
                    "wall_seconds the whole run's"}


def run_cross_embodiment_demo_bench(embodiments: str, settings: list[str], seeds: int = 3,
                                    max_steps: int | None = None, operator: str = DEFAULT_OPERATOR,
                                    stop_when_decided: bool = True, processes: int = 1) -> dict:
    """``b2d bench demos --embodiment ...``: ``settings`` are setting keys or task names (none: every task
    with a plan), ``embodiments`` 'all' or comma-separated names; both fail fast on an unknown name.
    A cell stops running seeds once its majority is decided (``stop_when_decided``; the CLI's
    ``--all-seeds`` turns that off): on 2 cores a full table is hours, and a settled cell's last seed
    changes nothing in it."""
    chosen = parse_embodiments(embodiments)
    tasks = parse_tasks(settings)

    def progress(cell: dict) -> None:
        errors = f" ({len(cell['errors'])} errors)" if cell["errors"] else ""
        early = f", decided after {cell['seeds']} of {cell['seeds_planned']} seeds" if cell["decided_early"] else ""
        cause = f", cause: {cell['failure_cause']}" if cell.get("failure_cause") else ""
        print(f"{cell['task']} on {cell['embodiment']}: {cell['successes']}/{cell['seeds']}{early}{cause}{errors}",
              file=sys.stderr, flush=True)     # stdout carries the JSON

    result = run_cross_embodiment_bench(tasks, chosen, seeds, max_steps, operator,
                                        stop_when_decided=stop_when_decided, progress=progress, processes=processes)
    return {**result, "markdown": markdown_table(result)}     # the README's table, paper cells in bold
