"""Per-step and per-episode metric records, convertible to plain dicts and numpy arrays.

StepRecord traces are stacked into HDF5 ``metrics/timeseries/*``; EpisodeRecord goes to
``metrics/episode`` (``to_json()`` for the JSON attribute, ``scalars()`` for scalar datasets).
Quantities that are undefined for an episode are None (NaN in ``scalars()``), never 0.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field, fields

import numpy as np


def _plain(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


@dataclass(frozen=True)
class StepRecord:
    step: int  # 1-based update index j
    time_s: float  # sum of dt up to j
    dt: float
    terminal: bool  # C_j
    dwell_s: float  # h_j
    stable: bool  # stable success reached at or before j
    stage_value: np.ndarray  # [K] bool: g_k(j)
    stage_latched: np.ndarray  # [K] bool: L_k after j's closure
    stage_valid: np.ndarray  # [K] bool: g_k(j) and dependencies latched
    current_depth: int
    latched_depth: int
    drop: bool
    high_speed: bool
    violation: bool  # V_j
    grasp_score: np.ndarray  # [O] float: G_{o,j} per grasp object
    tool_held: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))  # [C] candidate tools held

    def to_dict(self) -> dict:
        return {f.name: _plain(getattr(self, f.name)) for f in fields(self)}


TRACE_DTYPES = {"step": np.int64, "time_s": np.float64, "dt": np.float64, "terminal": bool, "dwell_s": np.float64,
                "stable": bool, "stage_value": bool, "stage_latched": bool, "stage_valid": bool,
                "current_depth": np.int32, "latched_depth": np.int32, "drop": bool, "high_speed": bool,
                "violation": bool, "grasp_score": np.float64, "tool_held": bool}
# also in the traces, computed at the end (evaluation/motion.py): joint_{vel,acc,jerk,effort}_rms [T], the
# RMS over robot joints per update, NaN where not available


def stack_steps(steps: list[StepRecord], n_stages: int, n_grasp: int, n_tools: int = 0) -> dict[str, np.ndarray]:
    """One array per quantity: [T] for scalars, [T, K] for stages, [T, O] for grasp scores, [T, C] for
    candidate tools."""
    width = {"stage_value": n_stages, "stage_latched": n_stages, "stage_valid": n_stages, "grasp_score": n_grasp,
             "tool_held": n_tools}
    out = {}
    for name, dtype in TRACE_DTYPES.items():
        values = [getattr(s, name) for s in steps]
        shape = (len(steps), width[name]) if name in width else (len(steps),)
        out[name] = np.array(values, dtype=dtype).reshape(shape)
    return out


@dataclass(frozen=True)
class EpisodeRecord:
    labels: dict  # task / policy / channel / episode ids given to the evaluator
    success: bool  # S_e
    t_stable: float | None
    steps_to_stable: int | None  # physics-step updates up to j_stable
    control_steps_to_stable: int | None
    policy_queries_to_stable: int | None
    isr_ever: bool  # I_e
    success_final: bool  # F_e
    n_steps: int  # n_e
    duration_s: float
    control_steps: int | None
    policy_queries: int | None
    dwell_s: float
    termination: str  # stable_success | horizon | error | whatever the runner reported
    error: str | None
    stage_ids: list[str]
    stage_latched: list[bool]  # L_{e,k}
    stage_latched_at_s: list[float | None]
    stage_final: list[bool]  # g_k(n_e)
    stage_final_valid: list[bool]  # g_k(n_e) and A_k(n_e)
    lscr: float | None
    cscr: float | None
    latched_depth: int
    current_depth: int
    max_depth: int
    drop: bool  # D_e
    high_speed: bool  # H_e
    hard_violation: bool  # B_e
    safe_success: bool  # S_e (1 - B_e)
    violation_steps: int  # sum_j V_j
    violation_events: int  # rising edges of V
    gsi: float | None
    gsi_mean: float | None
    t_expert: float | None
    te: float | None
    grasp_objects: list[str] = field(default_factory=list)
    # tool use (None: no stage names tools / no switch attempted); lists follow tool_stage_ids
    tsa: float | None = None
    tool_stage_ids: list[str] = field(default_factory=list)
    tool_selected: list[str | None] = field(default_factory=list)  # first held candidate per stage
    tool_correct: list[bool] = field(default_factory=list)
    tool_candidates: list[str] = field(default_factory=list)  # columns of the tool_held trace
    tssr: float | None = None
    tool_switch_attempts: int = 0
    tool_switch_successes: int = 0
    # robot motion: RMS over updates and joints (None: no robot state observed)
    joint_vel_rms: float | None = None
    joint_acc_rms: float | None = None
    joint_jerk_rms: float | None = None
    joint_effort_rms: float | None = None

    def to_dict(self) -> dict:
        """Flat plain dict: the labels first, then every field (JSON-serialisable)."""
        body = {k: _plain(v) for k, v in asdict(self).items() if k != "labels"}
        clash = set(self.labels) & set(body)
        if clash:
            raise ValueError(f"episode labels {sorted(clash)} clash with record fields")
        return {**_plain(self.labels), **body}

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), sort_keys=True, allow_nan=False)

    def scalars(self) -> dict[str, float | int | bool]:
        """Numeric scalar fields (None -> NaN) for scalar HDF5 datasets."""
        out = {}
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name in ("labels", "termination", "error") or isinstance(v, list):
                continue
            out[f.name] = math.nan if v is None else v
        return out
