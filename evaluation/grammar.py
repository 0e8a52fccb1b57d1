"""The condition grammar shared by every task: combinators, stage references and the predicate registry.

A condition is one of
    {all: [cond, ...]}   {any: [cond, ...]}   {not: cond}
    {stage: stage_id}    current value of another stage's predicate at this update
    {latched: stage_id}  whether that stage is latched after this update's closure (terminal only)
    {<predicate>: {args}}
Every child is evaluated at every update (no short-circuit), so stateful predicates see each step.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from evaluation.args import ArgReader
from evaluation.condition import Condition
from evaluation.errors import TaskSpecError, one_of
from evaluation.state import TaskContext

COMBINATORS = ("all", "any", "not", "stage", "latched")


PREDICATES: dict[str, Callable[[ArgReader], Condition]] = {}


def register(name: str):
    """Class decorator: make a predicate available under ``name`` in task files."""

    def decorate(cls):
        if name in COMBINATORS or name in PREDICATES:
            raise ValueError(f"predicate name {name!r} is taken")
        cls.name = name
        PREDICATES[name] = cls
        return cls

    return decorate


class All(Condition):
    def __init__(self, items: list[Condition]):
        self.items = items

    def children(self):
        return self.items

    def __call__(self, step):
        return all([c(step) for c in self.items])


class Any_(Condition):
    def __init__(self, items: list[Condition]):
        self.items = items

    def children(self):
        return self.items

    def __call__(self, step):
        return any([c(step) for c in self.items])


class Not(Condition):
    def __init__(self, item: Condition):
        self.item = item

    def children(self):
        return (self.item,)

    def __call__(self, step):
        return not self.item(step)


@dataclass
class StageRef(Condition):
    stage_id: str

    def __call__(self, step):
        return bool(step.stage_value[self.stage_id])


@dataclass
class LatchedRef(Condition):
    stage_id: str

    def __call__(self, step):
        return bool(step.latched[self.stage_id])


@dataclass
class CompileScope:
    """What a condition may refer to while compiling, and the stage ids it did refer to."""

    context: TaskContext
    stage_ids: Sequence[str] = ()
    source: str | None = None
    allow_latched: bool = True
    stage_refs: set[str] = field(default_factory=set)

    def _stage(self, key: str, body: Any, path: str) -> str:
        if not isinstance(body, str) or body not in self.stage_ids:
            raise TaskSpecError(f"{path}.{key}", f"a stage id {one_of(self.stage_ids)}", body, self.source)
        self.stage_refs.add(body)
        return body

    def compile(self, spec: Any, path: str) -> Condition:
        if not isinstance(spec, Mapping) or len(spec) != 1:
            expected = f"a mapping with one key: {', '.join(COMBINATORS)} or a predicate {one_of(PREDICATES)}"
            raise TaskSpecError(path, expected, spec, self.source)
        ((key, body),) = spec.items()
        if key in ("all", "any"):
            if not isinstance(body, list) or not body:
                raise TaskSpecError(f"{path}.{key}", "a non-empty list of conditions", body, self.source)
            items = [self.compile(c, f"{path}.{key}[{i}]") for i, c in enumerate(body)]
            return All(items) if key == "all" else Any_(items)
        if key == "not":
            return Not(self.compile(body, f"{path}.not"))
        if key == "stage":
            return StageRef(self._stage(key, body, path))
        if key == "latched":
            if not self.allow_latched:
                raise TaskSpecError(f"{path}.latched", "no latched reference inside a stage predicate "
                                    "(use depends_on)", body, self.source)
            return LatchedRef(self._stage(key, body, path))
        if key not in PREDICATES:
            expected = f"a combinator ({', '.join(COMBINATORS)}) or a predicate {one_of(PREDICATES)}"
            raise TaskSpecError(f"{path}.{key}", expected, key, self.source)
        reader = ArgReader(key, body, self, f"{path}.{key}")
        predicate = PREDICATES[key](reader)
        reader.done()
        return predicate

