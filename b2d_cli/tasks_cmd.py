"""`b2d tasks show <task>`: one task's stage graph (stages, predicates, dependencies, terminal).
`b2d tasks check [task...]`: can the arms reach every target of the layout."""

from __future__ import annotations

import json

import click

from sim import registry


def _flow(condition) -> str:
    """A condition on one line, in the task file's own (YAML flow) notation."""
    if isinstance(condition, dict):
        return "{" + ", ".join(f"{k}: {_flow(v)}" for k, v in condition.items()) + "}"
    if isinstance(condition, list):
        return "[" + ", ".join(_flow(v) for v in condition) + "]"
    return str(condition)


def stage_graph(name: str) -> dict:
    """The compiled stage graph of a task: stages in dependency order with depth, plus the terminal."""
    from evaluation import EpisodeEvaluator
    from sim.tasks import load_task, task_context

    task = load_task(name)
    ev = EpisodeEvaluator(task.metrics, task_context(task), source=str(task.source))
    raw = {s["id"]: s for s in task.metrics.get("stages", [])}
    stages = [{"id": sid, "depth": ev.stages.depth[sid], "depends_on": ev.stages.depends_on[sid],
               "predicate": raw[sid]["predicate"], "tools": raw[sid].get("tools", [])}
              for sid in ev.stages.latch_order]
    return {"task": task.name, "display_name": task.display_name, "paper_embodiment": task.paper_embodiment,
            "instruction": task.instruction, "joints": task.joint_names, "stages": stages,
            "terminal": task.metrics["terminal"], "dwell_s": ev.dwell.dwell_s,
            "expert_horizon_steps": ev.expert_horizon}


@click.group("tasks")
def tasks() -> None:
    """Inspect task files."""


@tasks.command("show")
@click.argument("task")
@click.option("--json", "as_json", is_flag=True, help="Print the stage graph as JSON.")
def show(task: str, as_json: bool) -> None:
    """Print one task's stage graph: stages (dependency order), predicates, dependencies, terminal."""
    registry.validate_name("task", task)
    graph = stage_graph(task)
    if as_json:
        click.echo(json.dumps(graph, indent=2))
        return
    click.echo(f"{graph['task']}  ({graph['display_name']}, paper embodiment {graph['paper_embodiment']})")
    click.echo(f"  instruction: {graph['instruction']}")
    if graph["joints"]:
        click.echo(f"  joints: {', '.join(graph['joints'])}")
    click.echo(f"  stages ({len(graph['stages'])}, in dependency order):")
    for st in graph["stages"]:
        deps = ", ".join(st["depends_on"]) or "-"
        click.echo(f"    [{st['depth']}] {st['id']}  <- {deps}")
        click.echo(f"        {_flow(st['predicate'])}")
        if st["tools"]:
            click.echo(f"        tools: {_flow(st['tools'])}")
    click.echo(f"  terminal (dwell {graph['dwell_s']} s, expert horizon {graph['expert_horizon_steps']} steps):")
    terminal = graph["terminal"]
    for item in terminal["all"] if isinstance(terminal, dict) and list(terminal) == ["all"] else [terminal]:
        click.echo(f"    {_flow(item)}")


@tasks.command("check")
@click.argument("task", nargs=-1)
@click.option("--embodiment", default=None, help="Embodiment to check on (default: each task's paper embodiment).")
@click.option("--json", "as_json", is_flag=True, help="Print the reach report as JSON.")
def check(task: tuple[str, ...], embodiment: str | None, as_json: bool) -> None:
    """Can the arms reach every target of a task's layout (objects, links, points, zones)?
    Checks all 26 tasks when none is named; exits 1 when a target is out of reach."""
    from sim.scene.builder import build_scene
    from sim.scene.reach import check_reach
    from sim.scene.sample import nominal_sample
    from sim.tasks import load_task

    names = list(task) or registry.names("tasks")
    for name in names:
        registry.validate_name("task", name)
    if embodiment:
        registry.validate_name("embodiment", embodiment)
    report, missed = [], 0
    for name in names:
        spec = load_task(name)
        emb = embodiment or spec.paper_embodiment
        reaches = check_reach(build_scene(spec, emb, nominal_sample(spec)))
        rows = [{"target": r.target.name, "arms": list(r.sides), "best_error_m": round(r.pos_err_m, 4)}
                for r in reaches]
        missed += sum(not r.reachable for r in reaches)
        report.append({"task": name, "embodiment": emb, "targets": rows})
    if as_json:
        click.echo(json.dumps(report, indent=2))
    else:
        for entry in report:
            out = [r for r in entry["targets"] if not r["arms"]]
            status = "all reachable" if not out else f"{len(out)} out of reach"
            click.echo(f"{entry['task']} on {entry['embodiment']}: {len(entry['targets'])} targets, {status}")
            for r in out:
                click.echo(f"    {r['target']}: best miss {1000 * r['best_error_m']:.1f} mm")
    raise SystemExit(1 if missed else 0)
