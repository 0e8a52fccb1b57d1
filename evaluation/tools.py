"""Tool-use diagnostics (paper, "Tool-use and motion diagnostics"): tool selection accuracy (TSA) and
tool switch success rate (TSSR). Enabled only when stages name tools:

    tool_use: {classes: {pourer: [soy_sauce, olive_oil]}, switch_timeout_s: 10.0}   # optional block
    stages:
      - {id: soy_poured, predicate: ..., tools: [soy_sauce]}        # object ids and/or {class: name}

"Held" is the grasp diagnostics' proxy (``grasp.lifted_and_held``, thresholds of the task's grasp
block); the tools (switches, ``tool_held`` trace) are the objects the stages' tools name.

Selection. A stage is eligible from the update its dependencies are all latched up to the update it
latches. Its selection is the first task object held while it is eligible: a held object in its
allowed set counts at once (also one already held when it became eligible, e.g. a ladle used for
two stages); any other object counts only if it was grasped while the stage was eligible and fits
no other eligible stage (so carrying the previous object, e.g. a bowl held in the other hand, or
taking the tool of a parallel stage, is not a wrong selection). Objects that never lift (fixed
furniture, articulated doors) are never held. TSA = correct selections / annotated stages; a stage
without a selection is incorrect.

Switch. When a held tool A is released, a switch window of ``switch_timeout_s`` opens. It is an
attempt once a hand touches another tool B (contact, not palm distance: putting the last tool
down beside another is no attempt). It succeeds when A has come to rest unheld without a drop (the
safety block's drop line) and B has been held for hold_min_s, both before the timeout; it fails on
a drop of A, at the timeout, or when the episode ends first. Re-grasping A before reaching another tool
closes the window without an attempt. TSSR = successes / attempts, None without an attempt.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from evaluation.errors import TaskSpecError, one_of
from evaluation.grasp import lifted_and_held, steady
from evaluation.safety import SafetyMonitor
from evaluation.state import HANDS, contact
from evaluation.step import EvalStep

TOOL_USE_KEYS = ("classes", "switch_timeout_s")
HAND_NAMES = tuple(f"{h}_hand" for h in HANDS)
DEFAULT_SWITCH_TIMEOUT_S = 10.0  # b2d's choice: the paper names a timeout but gives no value


def _names(raw: Any, objects: Sequence[str], classes: Mapping[str, list[str]], field: str,
           source: str | None, allow_classes: bool) -> list[str]:
    """A non-empty list of object ids (and, where allowed, {class: name}) resolved to object ids."""
    what = "a non-empty list of object ids" + (" and/or {class: name}" if allow_classes else "")
    if not isinstance(raw, list) or not raw:
        raise TaskSpecError(field, what, raw, source)
    out: list[str] = []
    for i, item in enumerate(raw):
        if allow_classes and isinstance(item, Mapping):
            if set(item) != {"class"}:
                raise TaskSpecError(f"{field}[{i}]", "{class: name}", dict(item), source)
            if not isinstance(item["class"], str) or item["class"] not in classes:
                raise TaskSpecError(f"{field}[{i}].class", f"a tool class from metrics.tool_use.classes "
                                    f"{one_of(classes)}", item["class"], source)
            out += classes[item["class"]]
        elif isinstance(item, str) and item in objects:
            out.append(item)
        else:
            raise TaskSpecError(f"{field}[{i}]", f"an object {one_of(objects)}"
                                + (" or {class: name}" if allow_classes else ""), item, source)
    return list(dict.fromkeys(out))


def parse_tool_use(raw: Any, stages: Sequence[Mapping], objects: Sequence[str], source: str | None = None,
                   field: str = "metrics") -> tuple[dict[str, list[str]], float]:
    """Each annotated stage's allowed tools ({stage id: [object, ...]}) and the switch timeout."""
    block = {} if raw is None else raw
    if not isinstance(block, Mapping):
        raise TaskSpecError(f"{field}.tool_use", f"a mapping with keys {list(TOOL_USE_KEYS)}", block, source)
    for key in block:
        if key not in TOOL_USE_KEYS:
            raise TaskSpecError(f"{field}.tool_use.{key}", f"a tool_use key {one_of(TOOL_USE_KEYS)}", key, source)
    classes_raw = block.get("classes", {}) or {}
    if not isinstance(classes_raw, Mapping):
        raise TaskSpecError(f"{field}.tool_use.classes", "a mapping of class name -> [object, ...]", classes_raw,
                            source)
    classes = {name: _names(members, objects, {}, f"{field}.tool_use.classes.{name}", source, False)
               for name, members in classes_raw.items()}
    timeout = block.get("switch_timeout_s", DEFAULT_SWITCH_TIMEOUT_S)
    if isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or not 0 < timeout < float("inf"):
        raise TaskSpecError(f"{field}.tool_use.switch_timeout_s", "a positive number of seconds", timeout, source)
    allowed = {st["id"]: _names(st["tools"], objects, classes, f"{field}.stages[{i}].tools", source, True)
               for i, st in enumerate(stages) if isinstance(st, Mapping) and "tools" in st}
    return allowed, float(timeout)


@dataclass
class _Switch:
    """An open switch window after releasing ``tool``."""

    tool: str
    opened_s: float
    attempted: bool = False
    settled: bool = False
    dropped: bool = False


class ToolUseMonitor:
    """TSA and TSSR of one episode; ``update`` once per evaluator update after the stage closure."""

    def __init__(self, allowed: dict[str, list[str]], depends_on: Mapping[str, list[str]], objects: Sequence[str],
                 timeout_s: float, grasp_cfg: Mapping[str, float], safety: SafetyMonitor):
        self.allowed, self.depends_on, self.timeout_s = allowed, depends_on, timeout_s
        self.stages = list(allowed)
        self.candidates = list(dict.fromkeys(t for tools in allowed.values() for t in tools))
        self.others = [o for o in objects if o not in self.candidates]  # selectable, never switched to
        self.cfg, self.safety = dict(grasp_cfg), safety
        self.reset()

    def reset(self) -> None:
        self.clock_s = 0.0
        self.hold_s = dict.fromkeys(self.candidates, 0.0)
        self.carried: dict[str, set[str]] = {}  # stage -> objects held since before it became eligible
        self.selected: dict[str, str] = {}
        self.correct: dict[str, bool] = {}
        self.switch: _Switch | None = None
        self.attempts = self.successes = 0

    def _held(self, s: EvalStep, names: Sequence[str]) -> list[str]:
        c = self.cfg
        return [t for t in names if lifted_and_held(s, t, c["lift_min"], c["hand_max_dist"])]

    def update(self, s: EvalStep, latched: Mapping[str, bool], newly_latched: Sequence[str]) -> list[bool]:
        """Advance one update after the stage closure (``latched``; ``newly_latched`` in this update);
        returns which candidate tools are held now (the ``tool_held`` trace)."""
        self.clock_s += s.dt
        tools_held = self._held(s, self.candidates)
        released = [t for t in self.candidates if self.hold_s[t] > 0 and t not in tools_held]
        for t in self.candidates:
            self.hold_s[t] = self.hold_s[t] + s.dt if t in tools_held else 0.0
        eligible = [k for k in self.stages if k not in self.correct and (not latched[k] or k in newly_latched)
                    and all(latched[d] for d in self.depends_on[k])]
        if eligible:    # other objects are looked at only while a selection is open
            others = [o for o in self.others if o in s.state.objects]    # the tools must be there; others may not
            self._select(eligible, tools_held + self._held(s, others))
        self._switch(s, tools_held, released, self.clock_s)
        return [t in tools_held for t in self.candidates]

    def _select(self, eligible: list[str], held_now: list[str]) -> None:
        fits_any = {t for k in eligible for t in self.allowed[k]}
        for k in eligible:
            carried = self.carried.setdefault(k, set(held_now))
            carried &= set(held_now)      # released once: a later grasp is a selection
            fitting = [t for t in held_now if t in self.allowed[k]]
            other = [t for t in held_now if t not in fits_any and t not in carried]
            if fitting or other:
                self.selected[k] = (fitting or other)[0]
                self.correct[k] = bool(fitting)

    def _switch(self, s: EvalStep, held_now: list[str], released: list[str], now: float) -> None:
        sw = self.switch
        if sw is None:
            if released:
                self.switch = _Switch(released[0], now)
            return
        a = sw.tool
        if a in held_now:
            if not sw.attempted:        # re-grasped the same tool: no switch
                self.switch = None
                return
            sw.settled = False
        elif self.safety.dropped(s.state, a):
            sw.dropped = True
        elif steady(s.obj(a), self.cfg):
            sw.settled = True
        if not sw.attempted:
            sw.attempted = any(contact(s.state, t, h) for t in self.candidates if t != a for h in HAND_NAMES)
            self.attempts += int(sw.attempted)
        if not sw.attempted:
            if now - sw.opened_s > self.timeout_s:
                self.switch = None
            return
        grasped = any(self.hold_s[t] >= self.cfg["hold_min_s"] for t in held_now if t != a)
        if sw.dropped or now - sw.opened_s > self.timeout_s:
            self.switch = None
        elif sw.settled and grasped:
            self.successes += 1
            self.switch = None

    # -- episode values ---------------------------------------------------------------------------
    @property
    def tsa(self) -> float | None:
        return sum(self.correct.values()) / len(self.stages) if self.stages else None

    @property
    def tssr(self) -> float | None:
        """An attempt still open when the episode ends counts as failed."""
        return self.successes / self.attempts if self.attempts else None
