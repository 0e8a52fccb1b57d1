"""A task file's parsed YAML with its demonstration plan replaced, for tests of plan steps."""

import yaml

from sim.tasks import load_task


def task_file_with_plan(task: str, steps: list[dict]) -> dict:
    """``task``'s file as parsed YAML, its `demo_plan` replaced by ``steps`` (parse it with `parse_task`)."""
    raw = yaml.safe_load(load_task(task).source.read_text())
    raw["demo_plan"] = list(steps)
    return raw
