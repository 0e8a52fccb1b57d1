"""`b2d bench demos --embodiment ...`: one task's `demo_plan` run on other embodiments than its paper one.

For each chosen task and embodiment (a *cell*) the scripted operator records demonstration seeds
0..N-1 (the same scene samples as the paper setting's, `teleop.demos.record_demonstrations`) and the
evaluator's stable successes are counted. A cell that cannot run (its scene does not build, an
episode raises) reports its errors and the others go on. Each cell also carries a kinematic dry run
of the plan (`plan_reach`): the wrist path the operator plans on seed 0's scene, tracked by the arm's
own IK as the direct joint path does, and where it falls short of the planned pose: a cell whose arm
strays far from the plan fails for its arm, not its hand (a heuristic: paper settings that succeed can
stray too, e.g. microwave_bowl_loading's UR5 left arm, 8 cm at the far end of the door's arc).

The goal the issue sets: a task's plan succeeds on a majority of seeds on at least
``GOAL_EMBODIMENTS`` of the twelve embodiments.
"""

from __future__ import annotations

import logging
import tempfile
import time
from pathlib import Path

import numpy as np

from episodes.workers import map_in_processes
from sim.embodiment.description import load_embodiment
from sim.errors import UnknownNameError
from sim.registry import SETTING_SEPARATOR, names, parse_setting_key, validate_name
from sim.scene.builder import demonstration_scene
from sim.tasks import has_finished_plan, load_task
from teleop.demos import DEFAULT_OPERATOR, OPERATORS, record_demonstrations
from teleop.recorder import episode_horizon, home
from teleop.scripted_operator import IK_ITERS, ScriptedOperator

log = logging.getLogger(__name__)
ALL = "all"
GOAL_EMBODIMENTS = 4            # the goal: a majority of seeds on at least this many embodiments
OFF_PATH_M = 0.01               # dry run: a step whose tracked wrist is this far from the plan is off the path
FRESH_IK_ITERS = 300            # the worst pose solved from home (as sim/scene/reach.py)
# a side whose dry-run path is this far off at worst and off (OFF_PATH_M) on more steps than this strays:
# a cell without a majority fails for its arm then, else for its hand (paper settings that succeed come
# 2-3 cm off on a few steps)
STRAY_M = 0.03
STRAY_STEPS = 20
MULTI_STARTS = 16               # a straying side's worst pose solved from this many random joint seeds


def parse_embodiments(value: str) -> list[str]:
    """``all`` or comma-separated embodiment names -> names (catalog order for ``all``); an unknown name
    fails here, listing the valid ones."""
    if value.strip() == ALL:
        return names("embodiments")
    chosen = [v.strip() for v in value.split(",") if v.strip()]
    if not chosen:
        raise UnknownNameError("embodiment", value, [ALL, *names("embodiments")])
    for name in chosen:
        validate_name("embodiment", name)
    return list(dict.fromkeys(chosen))


def recordable_tasks() -> list[str]:
    """Tasks with a finished `demo_plan` (catalog order; a draft runs only when named)."""
    return [t for t in names("tasks") if has_finished_plan(t)]


def parse_tasks(keys: list[str] | tuple[str, ...] | None) -> list[str]:
    """Setting keys (their task part counts) or task names -> task names; none: every task with a plan.
    Unknown names fail here, listing the valid ones."""
    if not keys:
        return recordable_tasks()
    tasks = []
    for key in keys:
        tasks.append(parse_setting_key(key).task if SETTING_SEPARATOR in key else validate_name("task", key))
    return list(dict.fromkeys(tasks))


def plan_reach(task: str, embodiment: str, index: int = 0) -> dict:
    """Kinematic dry run of the task's plan on the embodiment, demonstration ``index``'s scene: the
    operator plans its timeline on the homed scene, then each side's arm IK tracks the planned wrist
    pose step by step (warm-started, solved again from home on a miss, as ``ScriptedOperator.act``),
    without physics (a hand setting off for an object looks for it where the plan leaves it by then),
    up to the end of the plan's last step (the return home after it comes after the
    evaluator's reach-and-stop) or the episode horizon, whichever is first. Reports, per side, the
    worst position error, how many steps end more than OFF_PATH_M off the plan, on how many steps the
    solve from home was kept (``from_home_steps``), the worst pose's error when solved afresh from
    home with more iterations (small: the tracking lost its IK branch on the way) and, for a side that
    strays, from MULTI_STARTS fixed random joint seeds (``worst_multistart_m``; small: reachable on another
    branch than home's, e.g. the UR5s' left arm on fridge_wine_interhand_pour's late lift; large: out of the
    arm's reach from this mount, e.g. the IIWA7's near-table poses inside its folded elbow).
    Every step is tracked: a warm start two steps old already sends the xArm7 into other branches."""
    scene = demonstration_scene(task, embodiment, index)
    data = home(scene)
    operator = ScriptedOperator()
    operator.reset(scene, data)
    horizon = episode_horizon(scene)       # what an episode runs at most; the plan may go on past it
    mounts = load_embodiment(embodiment).mounts
    out = {}
    for name, side in operator.sides.items():
        kin, q = side["kin"], side["q"].copy()
        worst, worst_step, off, from_home = 0.0, 0, 0, 0
        frames = side["timeline"].frames
        steps = range(0, min(frames[-2].end_step if len(frames) > 1 else 0, horizon))

        def planned_by_arrival(name: str, approach: slice, side=side) -> np.ndarray:
            # a hand setting off for an object looks for it where the plan leaves it by the time the hand
            # gets there, not where it lay (in physics: where it is): aimed where fruit_bowl_loading's bowl lay
            # before the right hand dragged it, the UR5s' left arms "strayed" 9-27 cm, the paper's too
            return operator.planned_by_arrival(side, data, name, approach)

        for step in steps:
            operator.reaim(side, data, step, where=planned_by_arrival)
            pos, quat, _ = side["timeline"].at(step)
            result = kin.ik_tracking(pos, quat, q, side["q_home"], max_iters=IK_ITERS)
            from_home += result.from_home
            q = result.q
            if result.pos_err_m > worst:
                worst, worst_step = result.pos_err_m, step
            off += result.pos_err_m > OFF_PATH_M
        pos, quat, _ = side["timeline"].at(worst_step)
        fresh = kin.ik(pos, quat, side["q_home"], max_iters=FRESH_IK_ITERS)
        multi = None
        if worst > STRAY_M:
            rng = np.random.default_rng(0)     # fixed seeds: the report is deterministic
            multi = min(kin.ik(pos, quat, rng.uniform(kin.ik_lower, kin.ik_upper), max_iters=FRESH_IK_ITERS).pos_err_m
                        for _ in range(MULTI_STARTS))
        out[name] = {"worst_m": round(worst, 4), "worst_step": worst_step, "off_path_steps": off,
                     "from_home_steps": from_home, "tracked_steps": len(steps),
                     "worst_from_home_m": round(fresh.pos_err_m, 4),
                     # where the worst pose is, from the arm's base: near it (inside the arm's fold) or far
                     "worst_target_from_base_m": [round(float(v), 3) for v in pos - mounts[name].pos],
                     "worst_multistart_m": None if multi is None else round(multi, 4)}
    return out


def decided(successes: int, failures: int, seeds: int) -> bool:
    """Whether a cell's majority (more than half of ``seeds``) is settled whatever the rest do."""
    return 2 * successes > seeds or 2 * failures >= seeds


def stray_sides(reach: dict) -> list[str]:
    """The sides whose dry-run wrist path strays from the plan (``STRAY_M``, ``STRAY_STEPS``)."""
    return [s for s, r in reach.items() if r["worst_m"] > STRAY_M and r["off_path_steps"] > STRAY_STEPS]


def failure_cause(cell: dict) -> str | None:
    """Why a cell has no majority: 'error' (an episode or its scene raised), 'arm' (the dry run strays),
    'hand' (the arm follows the plan, the grasp or contact does not work out); None with a majority or
    without a dry run."""
    if cell["majority"]:
        return None
    if cell["errors"]:
        return "error"
    if "arm_strays" not in cell:
        return None
    return "arm" if cell["arm_strays"] else "hand"


def run_cell(task: str, embodiment: str, seeds: int, max_steps: int | None = None,
             operator: str = DEFAULT_OPERATOR, stop_when_decided: bool = False, dry_run: bool = True) -> dict:
    """One (task, embodiment) cell: seeds 0..seeds-1 recorded one by one; never raises. With
    ``stop_when_decided`` it stops once the majority of ``seeds`` is settled (of 3: after 2 successes or 2
    failures), so ``seeds`` (run) may be below ``seeds_planned`` and ``decided_early`` says so."""
    cell = {"task": task, "embodiment": embodiment, "paper": load_task(task).paper_embodiment == embodiment,
            "seeds": 0, "successes": 0, "success_seeds": [], "errors": []}
    t0 = time.process_time()
    if dry_run:
        try:
            cell["plan_reach"] = plan_reach(task, embodiment)
        except Exception as exc:        # a scene that does not build: reported, the cell still tries
            cell["errors"].append(f"plan_reach: {type(exc).__name__}: {exc}")
        else:   # the arms that do not follow the planned wrist path (out of reach, or a lost IK branch)
            cell["ik_off_path"] = [s for s, r in cell["plan_reach"].items() if r["off_path_steps"]]
            cell["arm_strays"] = stray_sides(cell["plan_reach"])
    steps = 0
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(seeds):
            try:
                (result,) = record_demonstrations(task, embodiment, 1, Path(tmp), max_steps=max_steps,
                                                  first_index=i, operator=operator, allow_draft=True)
            except Exception as exc:    # record_demonstrations catches per episode; this is a safety net
                log.exception("cell %s on %s, seed %d", task, embodiment, i)
                cell["errors"].append(f"seed {i}: {type(exc).__name__}: {exc}")
                result = None
            cell["seeds"] += 1
            if result is not None:
                steps += result.steps
                if result.error:
                    cell["errors"].append(f"seed {i}: {result.error}")
                if result.success:
                    cell["successes"] += 1
                    cell["success_seeds"].append(i)
                if result.path is not None:
                    result.path.unlink(missing_ok=True)      # keep the temporary folder small
            if stop_when_decided and decided(cell["successes"], cell["seeds"] - cell["successes"], seeds):
                break
    cell["seeds_planned"] = seeds
    cell["decided_early"] = cell["seeds"] < seeds     # the majority was settled before the last seed
    cell["majority"] = 2 * cell["successes"] > seeds
    cell["failure_cause"] = failure_cause(cell)
    cell["mean_steps"] = round(steps / max(cell["seeds"], 1), 1)
    cell["cpu_s"] = round(time.process_time() - t0, 1)
    return cell


def summarize(cells: list[dict], tasks: list[str], embodiments: list[str], seeds: int) -> dict:
    """The task x embodiment table ("successes/seeds run"), successes per embodiment and, per task,
    the embodiments where it succeeds on a majority of ``seeds``."""
    by = {(c["task"], c["embodiment"]): c for c in cells}
    table = {t: {e: f"{by[t, e]['successes']}/{by[t, e]['seeds']}" for e in embodiments if (t, e) in by}
             for t in tasks}
    majority = {t: [e for e in embodiments if (t, e) in by and by[t, e]["majority"]] for t in tasks}
    per_embodiment = {e: {"successes": sum(by[t, e]["successes"] for t in tasks if (t, e) in by),
                          "episodes": sum(by[t, e]["seeds"] for t in tasks if (t, e) in by),
                          "tasks_with_majority": sum(e in majority[t] for t in tasks),
                          "arm_stray_tasks": [t for t in tasks if (t, e) in by and by[t, e].get("arm_strays")]}
                      for e in embodiments}
    causes = [c.get("failure_cause") for c in cells]
    return {"table": table, "per_embodiment": per_embodiment,
            "failures_by_cause": {k: causes.count(k) for k in ("arm", "hand", "error") if k in causes},
            "embodiments_with_majority": {t: len(v) for t, v in majority.items()},
            "majority_embodiments": majority,
            "tasks_reaching_goal": [t for t in tasks if len(majority[t]) >= min(GOAL_EMBODIMENTS, len(embodiments))]}


def run_cross_embodiment_bench(tasks: list[str], embodiments: list[str], seeds: int = 3,
                               max_steps: int | None = None, operator: str = DEFAULT_OPERATOR,
                               stop_when_decided: bool = False, dry_run: bool = True, progress=None,
                               processes: int = 1) -> dict:
    """Every chosen task's plan on every chosen embodiment for ``seeds`` demonstration seeds, the cells in
    ``processes`` processes (reported in order). Names are checked before anything runs; a task without a
    plan is listed as such and skipped."""
    if operator not in OPERATORS:
        raise ValueError(f"operator: expected one of {list(OPERATORS)}, got {operator!r}")
    for t in tasks:
        validate_name("task", t)
    for e in embodiments:
        validate_name("embodiment", e)
    planned = [t for t in tasks if load_task(t).demo_plan]
    cells = []
    units = [(t, e, seeds, max_steps, operator, stop_when_decided, dry_run) for t in planned for e in embodiments]
    for cell in map_in_processes(run_cell, units, processes):
        cells.append(cell)
        if progress:
            progress(cell)
    return {"operator": operator, "seeds": seeds, "max_steps": max_steps, "stop_when_decided": stop_when_decided,
            "tasks": planned, "embodiments": embodiments,
            "without_plan": [t for t in tasks if t not in planned],
            "paper_embodiment": {t: load_task(t).paper_embodiment for t in planned},
            **summarize(cells, planned, embodiments, seeds), "cells": cells,
            "goal": f"a majority of {seeds} seeds on at least {GOAL_EMBODIMENTS} embodiments",
            "note": f"scripted operator ({operator}), demonstration seeds 0..{seeds - 1} of each task on each "
                    "embodiment" + (" (a cell stops once its majority is decided, so 'successes/seeds run')"
                                    if stop_when_decided else "")
                    + "; success = the evaluator's stable success (reach-and-stop)"}


def markdown_table(result: dict) -> str:
    """The task x embodiment table as Markdown: successes/seeds, the paper embodiment's cell in bold,
    and per task the count of embodiments with a majority."""
    embodiments = result["embodiments"]
    lines = ["| task | " + " | ".join(embodiments) + " | majority on |",
             "|---|" + "---|" * (len(embodiments) + 1)]
    for task in result["tasks"]:
        row = []
        for e in embodiments:
            value = result["table"][task].get(e, "")
            row.append(f"**{value}**" if value and e == result["paper_embodiment"][task] else value)
        lines.append(f"| {task} | " + " | ".join(row) + f" | {result['embodiments_with_majority'][task]} |")
    return "\n".join(lines)


def dry_run_summary(cell: dict) -> str:
    """One line: how far the plan's tracked wrist path strays (for the report)."""
    reach = cell.get("plan_reach") or {}
    return ", ".join(f"{s} {r['worst_m'] * 100:.1f} cm ({r['off_path_steps']}/{r['tracked_steps']} off)"
                     for s, r in reach.items())

