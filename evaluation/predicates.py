"""The predicate library shared by all tasks: compile YAML condition trees into callables.

Importing this module registers every predicate family. See grammar.py for the condition grammar
and each predicate class docstring for its arguments.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from evaluation import event_predicates, joint_predicates, placement_predicates, pose_predicates  # noqa: F401
from evaluation.errors import TaskSpecError
from evaluation.grammar import COMBINATORS, PREDICATES, CompileScope, Condition, register
from evaluation.state import TaskContext

__all__ = ["COMBINATORS", "Condition", "TaskSpecError", "compile_condition", "predicate_names", "register"]


def compile_condition(spec: Any, context: TaskContext, *, field: str = "condition", stage_ids: Sequence[str] = (),
                      source: str | None = None, allow_latched: bool = True) -> Condition:
    """Compile one condition tree; errors name ``field`` and the path below it."""
    return CompileScope(context, stage_ids, source, allow_latched).compile(spec, field)


def predicate_names() -> list[str]:
    return sorted(PREDICATES)

