"""The compiled-condition base class that predicates and combinators share.

Its own module so that the argument reader (evaluation/args.py) and the grammar that uses that reader
(evaluation/grammar.py) both depend on it without depending on each other.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

from evaluation.state import TaskContext
from evaluation.step import EvalStep


class Condition:
    """A compiled condition: call it once per update."""

    name = "condition"
    stateful = False

    def __call__(self, step: EvalStep) -> bool:
        raise NotImplementedError

    def children(self) -> Sequence[Condition]:
        return ()

    def reset(self) -> None:
        """Forget per-episode memory (stateful predicates override and call super)."""
        for child in self.children():
            child.reset()

    def restart(self) -> None:
        """Forget what has been counted but keep what is being observed (a key held down, a visit
        under way), so that only events beginning from the next update count: a stage's events count
        from when its dependencies hold (evaluation/stages.py). Stateful predicates override."""
        for child in self.children():
            child.restart()


class ConditionCompiler(Protocol):
    """What an argument reader needs from the grammar's compile scope: the task context, the file it
    reports errors against, and compiling a nested condition."""

    context: TaskContext
    source: str | None

    def compile(self, spec: Any, path: str) -> Condition: ...
