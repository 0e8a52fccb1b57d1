"""The one error type of the evaluation library: a task's metrics spec does not fit the grammar."""

from __future__ import annotations

from collections.abc import Iterable


class TaskSpecError(ValueError):
    """A metrics spec (or the context it refers to) is invalid.

    The message names the file (when known), the field path inside it, e.g.
    ``metrics.stages[2].predicate.inside.container``, and what was expected there.
    """

    def __init__(self, field: str, expected: str, got: object = None, source: str | None = None):
        self.field = field
        self.expected = expected
        self.got = got
        self.source = source
        where = f"{source}: {field}" if source else field
        message = f"{where}: expected {expected}"
        if got is not None:
            message += f", got {got!r}"
        super().__init__(message)

    def __reduce__(self):     # rebuilt from its parts when it crosses a process boundary (a worker's error)
        return type(self), (self.field, self.expected, self.got, self.source), self.__dict__


def one_of(names: Iterable[str]) -> str:
    """Format a list of valid names for an error message."""
    names = sorted(names)
    return "one of [" + ", ".join(names) + "]" if names else "a name, but none are defined"


class StateError(LookupError):
    """A SceneState lacks something a compiled predicate needs (an object, joint or hand)."""
