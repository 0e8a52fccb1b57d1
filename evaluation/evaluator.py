"""The executable evaluator: one instance per episode, updated once per executed physics step.

    ev = EpisodeEvaluator(task["metrics"], context, source="sim/catalog/tasks/x.yaml")
    for state, dt in rollout:
        ev.update(state, dt)
        if ev.stable: break          # reach-and-stop
    record, traces = ev.result(), ev.traces()

Spec keys (a task's ``metrics:`` block): terminal (required), stages, dwell_s (0.5), safety, grasp,
expert_horizon_steps (alias expert_time_step), sim_dt_s (for TE; default: the first update's dt),
tool_use (tool classes and the switch timeout, see evaluation/tools.py). Robot-motion diagnostics come
from ``SceneState.robot_qvel`` / ``robot_effort`` when the states carry them.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from evaluation.dwell import Dwell
from evaluation.errors import TaskSpecError, one_of
from evaluation.grammar import CompileScope
from evaluation.grasp import DEFAULTS as GRASP_DEFAULTS
from evaluation.grasp import GraspMonitor
from evaluation.motion import MotionMonitor
from evaluation.predicates import predicate_names  # noqa: F401  (registers every predicate)
from evaluation.records import EpisodeRecord, StepRecord, stack_steps
from evaluation.safety import SafetyMonitor
from evaluation.stages import StageGraph
from evaluation.state import SceneState, TaskContext
from evaluation.step import EvalStep
from evaluation.tools import ToolUseMonitor, parse_tool_use

log = logging.getLogger(__name__)

SPEC_KEYS = ("terminal", "stages", "dwell_s", "safety", "grasp", "expert_horizon_steps", "expert_time_step",
             "sim_dt_s", "description", "tool_use")


def _number(spec: Mapping, key: str, field: str, source: str | None, integer: bool = False,
            positive: bool = False):
    """A spec scalar: an integer >= 1, or a finite number >= 0 (> 0 when ``positive``)."""
    value = spec[key]
    bad = isinstance(value, bool) or not isinstance(value, int if integer else (int, float))
    if bad or not math.isfinite(value) or value < 0 or ((integer or positive) and value <= 0):
        kind = "a positive integer" if integer else "a positive number" if positive else "a number >= 0"
        raise TaskSpecError(f"{field}.{key}", kind, value, source)
    return value


class EpisodeEvaluator:
    """Terminal dwell, latched stages, safety and grasp diagnostics of one episode."""

    def __init__(self, metrics_spec: dict, context: TaskContext, source: str | None = None, *,
                 labels: Mapping[str, Any] | None = None, field: str = "metrics"):
        spec = metrics_spec
        if not isinstance(spec, Mapping):
            raise TaskSpecError(field, "a mapping (the task's metrics block)", spec, source)
        for key in spec:
            if key not in SPEC_KEYS:
                raise TaskSpecError(f"{field}.{key}", f"a metrics key {one_of(SPEC_KEYS)}", key, source)
        if "terminal" not in spec:
            raise TaskSpecError(f"{field}.terminal", "a terminal condition (required)", None, source)
        if "expert_horizon_steps" in spec and "expert_time_step" in spec:
            raise TaskSpecError(f"{field}.expert_time_step",
                                "only one of expert_horizon_steps / expert_time_step", None, source)
        self.context, self.source = context, source
        self.labels = dict(labels or {})
        self.dwell = Dwell(_number(spec, "dwell_s", field, source) if "dwell_s" in spec else 0.5)
        horizon_key = "expert_time_step" if "expert_time_step" in spec else "expert_horizon_steps"
        self.expert_horizon = _number(spec, horizon_key, field, source, integer=True) if horizon_key in spec else None
        self.sim_dt = _number(spec, "sim_dt_s", field, source, positive=True) if "sim_dt_s" in spec else None
        self.stages = StageGraph(spec.get("stages"), context, source, f"{field}.stages")
        self.terminal = CompileScope(context, self.stages.ids, source).compile(spec["terminal"], f"{field}.terminal")
        self.safety = SafetyMonitor(spec.get("safety"), context, source, f"{field}.safety")
        self.grasp = GraspMonitor(spec["grasp"], context, source, f"{field}.grasp") if "grasp" in spec else None
        allowed, timeout = parse_tool_use(spec.get("tool_use"), spec.get("stages") or [], list(context.objects),
                                          source, field)
        self.tools = ToolUseMonitor(allowed, self.stages.depends_on, list(context.objects), timeout,
                                    self.grasp.cfg if self.grasp else GRASP_DEFAULTS, self.safety) if allowed else None
        self.motion = MotionMonitor()
        self.reset()

    @property
    def stage_ids(self) -> list[str]:
        return list(self.stages.ids)

    @property
    def grasp_objects(self) -> list[str]:
        return list(self.grasp.objects) if self.grasp else []

    @property
    def tool_candidates(self) -> list[str]:
        """Columns of the ``tool_held`` trace: every object a stage's tools name."""
        return list(self.tools.candidates) if self.tools else []

    @property
    def stable(self) -> bool:
        """Stable success reached: under reach-and-stop the runner ends the episode now."""
        return self.dwell.stable

    def reset(self) -> None:
        """Start a new episode with the same compiled spec."""
        self.dwell.reset()
        self.stages.reset()
        self.terminal.reset()
        if self.grasp:
            self.grasp.reset()
        if self.tools:
            self.tools.reset()
        self.motion.reset()
        self.initial = self.context.initial
        self.latched = {k: False for k in self.stages.ids}
        self.latched_at: dict[str, float] = {}
        self.steps: list[StepRecord] = []
        self.first_dt: float | None = None
        self.control_steps = self.policy_queries = None
        self.control_at_stable = self.queries_at_stable = None

    def update(self, state: SceneState, dt: float, *, control_step: bool | None = None,
               policy_query: bool | None = None) -> StepRecord:
        """Evaluate one executed physics step that took ``dt`` seconds of simulation time."""
        try:
            dt = float(dt)
        except (TypeError, ValueError):
            raise ValueError(f"dt must be a positive finite number of seconds, got {dt!r}") from None
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive finite number of seconds, got {dt!r}")
        if self.initial is None:
            self.initial = state
        self.first_dt = dt if self.first_dt is None else self.first_dt
        if control_step is not None:
            self.control_steps = (self.control_steps or 0) + int(control_step)
        if policy_query is not None:
            self.policy_queries = (self.policy_queries or 0) + int(policy_query)
        step = EvalStep(state, self.context, self.initial, dt, {}, self.latched)
        values = self.stages.evaluate(step)
        now = self.dwell.elapsed + dt  # sum of dt up to this update
        newly = self.stages.latch(values, self.latched)
        for k in newly:
            self.latched_at[k] = now
        valid = self.stages.valid(values, self.latched)
        c = bool(self.terminal(step))
        was_stable = self.dwell.stable
        h = self.dwell.update(c, dt)
        if self.dwell.stable and not was_stable:
            self.control_at_stable, self.queries_at_stable = self.control_steps, self.policy_queries
        drop, fast = self.safety.drop(state), self.safety.high_speed(state)
        grasp = self.grasp.update(step) if self.grasp else np.zeros(0)
        tools = self.tools.update(step, self.latched, newly) if self.tools else ()
        self.motion.update(state.robot_qvel, state.robot_effort)
        ids = self.stages.ids
        record = StepRecord(
            step=self.dwell.steps, time_s=self.dwell.elapsed, dt=float(dt), terminal=c, dwell_s=h,
            stable=self.dwell.stable, stage_value=np.array([values[k] for k in ids], dtype=bool),
            stage_latched=np.array([self.latched[k] for k in ids], dtype=bool),
            stage_valid=np.array([valid[k] for k in ids], dtype=bool),
            current_depth=self.stages.max_depth(valid), latched_depth=self.stages.max_depth(self.latched),
            drop=drop, high_speed=fast, violation=drop or fast, grasp_score=grasp,
            tool_held=np.array(tools, dtype=bool))
        self.steps.append(record)
        return record

    def traces(self) -> dict[str, np.ndarray]:
        """Per-step quantities stacked over the episode; stage columns follow ``stage_ids``."""
        out = stack_steps(self.steps, len(self.stages), len(self.grasp_objects), len(self.tool_candidates))
        per_update, _ = self.motion.summary(out["dt"])
        out.update({f"joint_{q}_rms": v for q, v in per_update.items()})
        return out

    def result(self, *, termination: str | None = None, error: str | None = None) -> EpisodeRecord:
        """Episode-level record. ``error``: the rollout ended because evaluation could not proceed."""
        t = self.traces()
        n, k = len(self.steps), len(self.stages)
        success = self.dwell.stable
        last = self.steps[-1] if self.steps else None
        final = [bool(v) for v in last.stage_value] if last else [False] * k
        final_valid = [bool(v) for v in last.stage_valid] if last else [False] * k
        latched = [self.latched[s] for s in self.stages.ids]
        violation = t["violation"]
        events = int(np.count_nonzero(violation[1:] & ~violation[:-1]) + (violation[0] if n else 0))
        positive = t["grasp_score"][t["grasp_score"] > 0]
        drop, fast = bool(t["drop"].any()), bool(t["high_speed"].any())
        t_expert = None
        if self.expert_horizon is not None and (self.sim_dt or self.first_dt):
            t_expert = self.expert_horizon * (self.sim_dt or self.first_dt)
        if termination is None:
            termination = "error" if error else "stable_success" if success else "horizon"
        return EpisodeRecord(
            labels=dict(self.labels), success=success, t_stable=self.dwell.t_stable,
            steps_to_stable=self.dwell.stable_step, control_steps_to_stable=self.control_at_stable,
            policy_queries_to_stable=self.queries_at_stable, isr_ever=self.dwell.ever,
            success_final=self.dwell.last, n_steps=n, duration_s=self.dwell.elapsed,
            control_steps=self.control_steps, policy_queries=self.policy_queries, dwell_s=self.dwell.dwell_s,
            termination=termination, error=error, stage_ids=list(self.stages.ids), stage_latched=latched,
            stage_latched_at_s=[self.latched_at.get(s) for s in self.stages.ids], stage_final=final,
            stage_final_valid=final_valid, lscr=sum(latched) / k if k else None,
            cscr=sum(final_valid) / k if k else None,
            latched_depth=self.stages.max_depth(self.latched),
            current_depth=int(last.current_depth) if last else 0,
            max_depth=max(self.stages.depth.values(), default=0), drop=drop, high_speed=fast,
            hard_violation=drop or fast, safe_success=success and not (drop or fast),
            violation_steps=int(violation.sum()), violation_events=events,
            gsi=float(t["grasp_score"].max()) if self.grasp and n else None,
            gsi_mean=float(positive.mean()) if positive.size else None,
            t_expert=t_expert, te=t_expert / self.dwell.t_stable if success and t_expert else None,
            grasp_objects=self.grasp_objects, **self._tool_fields(),
            **{f"joint_{q}_rms": v for q, v in self.motion.summary(t["dt"])[1].items()})

    def _tool_fields(self) -> dict[str, Any]:
        tu = self.tools
        if tu is None:
            return {}
        return {"tsa": tu.tsa, "tool_stage_ids": list(tu.stages),
                "tool_selected": [tu.selected.get(k) for k in tu.stages],
                "tool_correct": [tu.correct.get(k, False) for k in tu.stages], "tool_candidates": list(tu.candidates),
                "tssr": tu.tssr, "tool_switch_attempts": tu.attempts, "tool_switch_successes": tu.successes}


def evaluate_states(metrics_spec: dict, context: TaskContext, states: Sequence[SceneState],
                    dt: float | Sequence[float], *, source: str | None = None,
                    labels: Mapping[str, Any] | None = None,
                    stop_at_stable: bool = False) -> tuple[EpisodeRecord, dict[str, np.ndarray]]:
    """Evaluate a recorded state sequence; ``dt`` is one step length or one per state."""
    dts = [dt] * len(states) if isinstance(dt, (int, float)) else list(dt)
    if len(dts) != len(states):
        raise ValueError(f"{len(dts)} step lengths for {len(states)} states")
    ev = EpisodeEvaluator(metrics_spec, context, source, labels=labels)
    for state, d in zip(states, dts):
        ev.update(state, d)
        if stop_at_stable and ev.stable:
            break
    return ev.result(), ev.traces()
