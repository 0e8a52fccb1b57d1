"""The records contract: the per-episode columns a records file (parquet or CSV) must or may carry.

b2d's rollout parquet files satisfy it as written; a file made by hand from another benchmark's
published counts needs only the REQUIRED columns (README.md in this package is the reader's version).
"""

from __future__ import annotations

from dataclasses import dataclass

from evaluation.metrics import CHANNELS

CELL = ("task", "embodiment", "policy", "channel")  # one Table 2 count
ROW = ("task", "embodiment", "policy")              # one Table 2 row (one policy group of it)
EPISODE_KEY = (*CELL, "episode")                    # unique per episode


@dataclass(frozen=True)
class Column:
    name: str
    kind: str          # "text" | "flag" | "number" | "fraction" (a number in [0, 1]) | "any"
    doc: str


REQUIRED = (
    Column("task", "text", "task id or name (one Table 2 row per task and embodiment)"),
    Column("embodiment", "text", "arm+hand the task ran on"),
    Column("policy", "text", "policy name (one column group per policy)"),
    Column("channel", "text", "none, equi_only, inv_only or inv_equi (the paper's None, Equi., Inv., Full; "
                              "those four labels are accepted too)"),
    Column("episode", "any", "episode id, unique within its (task, embodiment, policy, channel) cell"),
    Column("success", "flag", "reach-and-stop stable success S_e: true/false or 1/0"),
)

OPTIONAL = (
    Column("lscr", "fraction", "latched stage completion LSCR_e; empty when the task has no stages"),
    Column("termination", "text", "stable_success, horizon or error; an error episode counts as a failure"),
    Column("seed", "number", "resolved episode seed"),
    Column("t_stable", "number", "seconds to stable success (successful episodes)"),
    Column("cscr", "fraction", "terminal-state stage completion CSCR_e"),
    Column("safe_success", "flag", "S_e (1 - B_e)"),
    Column("hard_violation", "flag", "B_e: a drop or a high-speed event"),
    Column("drop", "flag", "D_e"),
    Column("high_speed", "flag", "H_e"),
    Column("violation_steps", "number", "executed steps with a task-level violation"),
    Column("n_steps", "number", "executed evaluator updates n_e"),
    Column("isr_ever", "flag", "terminal predicate true at least once (I_e)"),
    Column("success_final", "flag", "terminal predicate true at the last update (F_e)"),
    Column("dwell_s", "number", "dwell time the episode was scored with"),
    Column("code_version", "text", "version of the code that produced the episode (provenance)"),
    Column("sensor_profile_hash", "text", "content hash of the sensor profile the policy observed through"),
    Column("horizon_rule", "text", "how the episode budget was set, e.g. 1.5x expert horizon"),
)

KINDS = {c.name: c.kind for c in (*REQUIRED, *OPTIONAL)}
# columns of evaluation.metrics.NEEDED a records file may leave out; metrics that read them are then
# reported as not available (None) instead of being computed from placeholders
DERIVED_FROM = {
    "t_succ": ("t_stable",), "SafeSR": ("safe_success",), "HVR": ("hard_violation",), "DropR": ("drop",),
    "HSR": ("high_speed",), "VSR_step": ("violation_steps", "n_steps"), "ISR_ever": ("isr_ever",),
    "SR_final": ("success_final",), "CSCR": ("cscr",), "mean_steps": ("n_steps",), "LSCR": ("lscr",),
}

LABELS = {"none": "None", "equi_only": "Equi.", "inv_only": "Inv.", "inv_equi": "Full"}
ALIASES = {**{c: c for c in CHANNELS}, **{label.lower(): c for c, label in LABELS.items()},
           **{label.lower().rstrip("."): c for c, label in LABELS.items()}}


class RecordsError(ValueError):
    """A records file breaks the contract: names the file, the column and the rows (0-based data rows)."""

    def __init__(self, problems: list[tuple[str, str, str, list]]):
        self.problems = problems
        lines = [f"{path}: column '{column}': {what}" + (f" (rows {_rows(rows)})" if rows else "")
                 for path, column, what, rows in problems]
        super().__init__("records refused:\n" + "\n".join(f"- {line}" for line in lines))


def _rows(rows: list, show: int = 10) -> str:
    shown = ", ".join(str(r) for r in rows[:show])
    return shown + (f", ... {len(rows) - show} more" if len(rows) > show else "")
