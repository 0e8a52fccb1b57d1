"""Stages: compiled stage predicates over an acyclic dependency graph, and their latching.

A stage latches at the first update where its predicate holds and every dependency is latched,
either earlier or in the same update's closure (paper, "Latched stage progress"). One pass in
topological order of ``depends_on`` computes that fixed point, because a stage's dependencies are
settled before it is visited.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Mapping
from typing import Any

from evaluation.errors import TaskSpecError, one_of
from evaluation.grammar import CompileScope, Condition
from evaluation.state import TaskContext
from evaluation.step import EvalStep

log = logging.getLogger(__name__)

STAGE_KEYS = ("id", "predicate", "depends_on", "description", "tools")  # tools: evaluation/tools.py
STAGE_ID = re.compile(r"^[A-Za-z_][A-Za-z0-9_.-]*$")


def _topological(ids: list[str], edges: dict[str, list[str]]) -> list[str]:
    """Order ids so that each comes after its edges' targets; a cycle raises _Cycle([a, b, ..., a])."""
    order: list[str] = []
    mark: dict[str, int] = {}  # 1 visiting, 2 done
    path: list[str] = []

    def visit(k: str) -> list[str] | None:
        if mark.get(k) == 2:
            return None
        if mark.get(k) == 1:
            return path[path.index(k):] + [k]
        mark[k] = 1
        path.append(k)
        for d in edges[k]:
            cycle = visit(d)
            if cycle:
                return cycle
        path.pop()
        mark[k] = 2
        order.append(k)
        return None

    for k in ids:
        cycle = visit(k)
        if cycle:
            raise _Cycle(cycle)
    return order


class _Cycle(Exception):
    def __init__(self, cycle: list[str]):
        self.cycle = cycle


class StageGraph:
    """The task's stages: ids, compiled predicates, dependencies, depth and evaluation orders."""

    def __init__(self, raw: Any, context: TaskContext, source: str | None = None, field: str = "metrics.stages"):
        raw = [] if raw is None else raw
        if not isinstance(raw, list):
            raise TaskSpecError(field, "a list of stages", raw, source)
        ids: list[str] = []
        for i, st in enumerate(raw):
            if not isinstance(st, Mapping):
                raise TaskSpecError(f"{field}[{i}]", f"a mapping with keys {list(STAGE_KEYS)}", st, source)
            for key in st:
                if key not in STAGE_KEYS:
                    raise TaskSpecError(f"{field}[{i}].{key}", f"a stage key {one_of(STAGE_KEYS)}", key, source)
            sid = st.get("id")
            if not isinstance(sid, str) or not STAGE_ID.match(sid) or sid in ids:
                raise TaskSpecError(f"{field}[{i}].id", "a unique identifier (letters, digits, _ . -)", sid, source)
            if "predicate" not in st:
                raise TaskSpecError(f"{field}[{i}].predicate", "a condition (required)", None, source)
            ids.append(sid)
        self.ids = ids
        self.index = {k: i for i, k in enumerate(ids)}
        self.predicates: dict[str, Condition] = {}
        self.depends_on: dict[str, list[str]] = {}
        refs: dict[str, list[str]] = {}
        for i, st in enumerate(raw):
            sid = st["id"]
            scope = CompileScope(context, ids, source, allow_latched=False)
            self.predicates[sid] = scope.compile(st["predicate"], f"{field}[{i}].predicate")
            refs[sid] = sorted(scope.stage_refs)
            deps = st.get("depends_on", []) or []
            if not isinstance(deps, list):
                raise TaskSpecError(f"{field}[{i}].depends_on", "a list of stage ids", deps, source)
            for j, d in enumerate(deps):
                if d not in ids or d == sid:
                    raise TaskSpecError(f"{field}[{i}].depends_on[{j}]", f"another stage id {one_of(ids)}", d, source)
            self.depends_on[sid] = list(dict.fromkeys(deps))
        self.latch_order = self._order(self.depends_on, field, "depends_on", "an acyclic dependency graph", source)
        self._stateful = {k for k, p in self.predicates.items() if self.depends_on[k] and _has_memory(p)}
        self.eval_order = self._order(refs, field, "predicate", "no cycle of {stage: ...} references", source)
        self.depth: dict[str, int] = {}
        for k in self.latch_order:
            self.depth[k] = 1 + max((self.depth[d] for d in self.depends_on[k]), default=0)

    def _order(self, edges, field, key, expected, source) -> list[str]:
        try:
            return _topological(self.ids, edges)
        except _Cycle as c:
            first = self.index[c.cycle[0]]
            raise TaskSpecError(f"{field}[{first}].{key}", expected, " -> ".join(c.cycle), source) from None

    def __len__(self) -> int:
        return len(self.ids)

    def reset(self) -> None:
        for p in self.predicates.values():
            p.reset()

    def evaluate(self, step: EvalStep) -> dict[str, bool]:
        """Each stage predicate once, in reference order; ``step.stage_value`` is filled as we go.
        A stage's events count from when its dependencies hold: until they are all latched, a stateful
        predicate (key presses, strikes, sequences) restarts at every update, forgetting what it has
        counted but not what it observes, so a button pressed, or held, before the mouse was in place
        is not the click that comes after (only a press that begins from the latching update on)."""
        values = step.stage_value
        for k in self.eval_order:
            if k in self._stateful and not all(step.latched[d] for d in self.depends_on[k]):
                self.predicates[k].restart()
            values[k] = bool(self.predicates[k](step))
        return dict(values)

    def latch(self, values: Mapping[str, bool], latched: dict[str, bool]) -> list[str]:
        """Same-step closure: latch every stage whose predicate holds and whose dependencies are latched."""
        new = []
        for k in self.latch_order:
            if not latched[k] and values[k] and all(latched[d] for d in self.depends_on[k]):
                latched[k] = True
                new.append(k)
        if new:
            log.debug("stages latched: %s", new)
        return new

    def valid(self, values: Mapping[str, bool], latched: Mapping[str, bool]) -> dict[str, bool]:
        """Predicate holds now and every dependency is latched (the CSCR condition)."""
        return {k: values[k] and all(latched[d] for d in self.depends_on[k]) for k in self.ids}

    def max_depth(self, flags: Mapping[str, bool]) -> int:
        """Longest dependency chain ending at a flagged stage (0 if none)."""
        return max((self.depth[k] for k in self.ids if flags[k]), default=0)


def _has_memory(condition: Condition) -> bool:
    return condition.stateful or any(_has_memory(c) for c in condition.children())
