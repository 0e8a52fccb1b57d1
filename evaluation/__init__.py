"""b2d evaluation: the predicate library, the executable episode evaluator and the metric suite.

A plain library on state snapshots (no simulator, no orchestration imports), after the paper's
appendix "Evaluation Metrics".
"""

from evaluation.errors import StateError, TaskSpecError
from evaluation.evaluator import EpisodeEvaluator, evaluate_states
from evaluation.predicates import compile_condition, predicate_names
from evaluation.records import EpisodeRecord, StepRecord
from evaluation.state import ObjectInfo, ObjectState, SceneState, TaskContext

__all__ = ["EpisodeEvaluator", "EpisodeRecord", "ObjectInfo", "ObjectState", "SceneState", "StateError",
           "StepRecord", "TaskContext", "TaskSpecError", "compile_condition", "evaluate_states", "predicate_names"]
