"""Raw recordings: the lightweight motion stream written while an operator drives the robot.

One HDF5 file per episode holding what replay needs to reproduce it exactly: the full MuJoCo
integration state after homing, the seed and resolved scene sample, and per control step the action
executed next followed by the post-step robot/object state and the evaluator state (paper:
"Online Teleoperation Setup"). Reading validates everything and names the file and field at fault.

Per step, ``step_flags`` holds the operator stream's ``StepFlag`` bits (teleop/streams/sanitizer.py:
dropped or out-of-order frames, non-finite keypoints, bad or unreachable wrist poses; 0 = clean) and
the optional ``step_reasons`` dataset the same steps' reasons as text, one per line ("" = clean).
Files written before ``step_reasons`` existed read with every reason "".
"""

from __future__ import annotations

import io
import json
import re
from dataclasses import dataclass, field, replace
from pathlib import Path

import h5py
import numpy as np

from episodes.atomic import atomic_path
from sim.errors import SpecError

RAW_SCHEMA = "b2d.raw/1"
RAW_NAME = re.compile(r"episode_(\d+)\.raw\.h5")


@dataclass
class RawRecording:
    task: str
    embodiment: str
    episode_id: str
    seed: int
    scene_sample: str                 # SceneSample JSON
    operator: str                     # "scripted" | "teleop:<adapter>"
    control_hz: int
    substeps: int
    initial_state: np.ndarray         # mj_getState(mjSTATE_INTEGRATION) after homing
    actuator_names: list[str]
    robot_joint_names: list[str]
    object_names: list[str]
    action: np.ndarray                # [T, nu] float64 absolute joint targets
    robot_qpos: np.ndarray            # [T, J] post-step
    robot_qvel: np.ndarray            # [T, J]
    object_pose: np.ndarray           # [T, N, 7] post-step, xyz + wxyz
    terminal: np.ndarray              # [T] bool evaluator terminal predicate
    stage_latched: np.ndarray         # [T, K] bool
    stage_ids: list[str]
    step_flags: np.ndarray            # [T] uint8, operator-stream flags (0 = clean)
    success: bool
    extra: dict = field(default_factory=dict)
    step_reasons: list[str] = field(default_factory=list)   # [T] why a step was flagged ("" = clean)
    hand_model: str = "generated"     # which hand geometry the scene was built with (replay rebuilds it)

    @property
    def num_steps(self) -> int:
        return int(self.action.shape[0])


_ARRAYS = ("initial_state", "action", "robot_qpos", "robot_qvel", "object_pose", "terminal",
           "stage_latched", "step_flags")
_ATTRS = ("task", "embodiment", "episode_id", "seed", "scene_sample", "operator", "control_hz",
          "substeps", "success")
_LISTS = ("actuator_names", "robot_joint_names", "object_names", "stage_ids")
REASONS = "step_reasons"      # optional: absent in files written before it existed


_ATTR_TYPES = {"task": str, "embodiment": str, "episode_id": str, "seed": int, "scene_sample": str,
               "operator": str, "control_hz": int, "substeps": int, "success": bool}
# accepted numpy kinds per array and the dtype named when refused: integer actions or states are a
# writer's mistake (joint targets are continuous), not something to round silently
_ARRAY_KINDS = {"initial_state": ("f", "float64"), "action": ("f", "float64"), "robot_qpos": ("f", "float64"),
                "robot_qvel": ("f", "float64"), "object_pose": ("f", "float64"), "terminal": ("b", "bool"),
                "stage_latched": ("b", "bool"), "step_flags": ("u", "uint8")}
_FINITE = ("initial_state", "robot_qpos", "robot_qvel", "object_pose")   # NaN there also disabled the drift check


def _json_attr(path: Path, f: h5py.File, key: str, default: str, kind: type):
    text = f.attrs.get(key, default)
    try:
        value = json.loads(text)
    except (TypeError, ValueError, RecursionError) as exc:
        raise SpecError(path, key, f"a JSON {kind.__name__} attribute", f"{type(exc).__name__}: {exc}"[:120]) from None
    if not isinstance(value, kind):
        raise SpecError(path, key, f"a JSON {kind.__name__} attribute", type(value).__name__)
    return value


def raw_episode_id(path: str | Path) -> str:
    """The episode id a raw recording's file name carries: `episode_<digits>.raw.h5`, as recorders
    name them. Anything else in a folder of recordings is refused, not taken in (issue 23)."""
    path = Path(path)
    match = RAW_NAME.fullmatch(path.name)
    if not match:
        raise SpecError(path, "<file name>", "a raw recording named 'episode_<digits>.raw.h5' (as `b2d record` "
                                             "and `b2d teleop` write them)", path.name)
    return match.group(1)


def write_raw(path: str | Path, rec: RawRecording) -> Path:
    path = Path(path)
    # what a reader would refuse is never written (an empty recording, NaN states)
    _check_consistency(path, replace(rec, step_reasons=rec.step_reasons or [""] * rec.num_steps))
    # built in memory (a recording is a few MB), then written by Python: a full disk is then a plain
    # OSError here. HDF5 itself cannot close a file whose writes failed, and its exit handler then
    # crashed the process (`b2d record` on a full disk: a segmentation fault, issue 23)
    image = io.BytesIO()
    with h5py.File(image, "w") as f:
        f.attrs["schema"] = RAW_SCHEMA
        for key in _ATTRS:
            f.attrs[key] = getattr(rec, key)
        f.attrs["extra"] = json.dumps(rec.extra, sort_keys=True)
        f.attrs["hand_model"] = rec.hand_model
        for key in _LISTS:
            f.attrs[key] = json.dumps(getattr(rec, key))
        for key in _ARRAYS:
            f.create_dataset(key, data=getattr(rec, key), compression="gzip", compression_opts=4)
        reasons = rec.step_reasons or [""] * rec.num_steps
        f.create_dataset(REASONS, data=np.array(reasons, dtype=h5py.string_dtype()), compression="gzip",
                         compression_opts=4)
    try:
        with atomic_path(path) as tmp:
            tmp.write_bytes(image.getbuffer())
    except OSError as exc:      # name the file: a bare "[Errno 28] No space left on device" does not
        raise OSError(exc.errno, exc.strerror, str(path)) from exc
    return path


def _read_values(path: Path, f: h5py.File) -> dict:
    if f.attrs.get("schema") != RAW_SCHEMA:
        raise SpecError(path, "schema", f"'{RAW_SCHEMA}'", f.attrs.get("schema"))
    values = {}
    for key in _ATTRS:
        if key not in f.attrs:
            raise SpecError(path, key, "an attribute")
        value = f.attrs[key]
        values[key] = value.item() if isinstance(value, np.generic) else value
        if not isinstance(values[key], _ATTR_TYPES[key]) or (key != "success" and isinstance(values[key], bool)):
            raise SpecError(path, key, f"an attribute of type {_ATTR_TYPES[key].__name__}",
                            f"{type(values[key]).__name__} {values[key]!r}"[:120])
    for key in _LISTS:
        values[key] = _json_attr(path, f, key, "[]", list)
        if not all(isinstance(v, str) for v in values[key]):
            raise SpecError(path, key, "a JSON list of names (strings)", values[key][:5])
    values["extra"] = _json_attr(path, f, "extra", "{}", dict)
    values["hand_model"] = str(f.attrs.get("hand_model", "generated"))   # absent before real hands existed
    for key in _ARRAYS:
        if key not in f:
            raise SpecError(path, key, "a dataset")
        if not isinstance(f[key], h5py.Dataset):
            raise SpecError(path, key, "a dataset", f"a {type(f[key]).__name__}")
        try:
            values[key] = f[key][()]
        except (OSError, ValueError, TypeError) as exc:
            raise SpecError(path, key, "readable data (file is truncated or corrupt)") from exc
        kind = np.asarray(values[key]).dtype.kind
        if kind not in _ARRAY_KINDS[key]:
            raise SpecError(path, key, f"a dataset of dtype {_ARRAY_KINDS[key][1]}",
                            str(np.asarray(values[key]).dtype))
    if REASONS in f:
        try:
            values[REASONS] = [str(r) for r in f[REASONS].asstr()[()]]
        except (OSError, TypeError, ValueError) as exc:
            raise SpecError(path, REASONS, "a readable dataset of UTF-8 strings [T]") from exc
    else:
        values[REASONS] = [""] * len(values["action"])
    return values


def read_raw(path: str | Path) -> RawRecording:
    """Load and validate a raw recording; every failure names the file and the field."""
    path = Path(path)
    if not path.is_file():
        raise SpecError(path, "<file>", "an existing raw recording file")
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise SpecError(path, "<file>", "a complete HDF5 raw recording (file is truncated or not HDF5)") from exc
    with f:
        try:
            values = _read_values(path, f)
        except SpecError:
            raise
        except Exception as exc:    # a damaged header or heap: HDF5 raises KeyError, OSError, RuntimeError...
            raise SpecError(path, "<file>", "a readable raw recording (the file is corrupt)",
                            f"{type(exc).__name__}: {str(exc)[:120]}") from None
    rec = RawRecording(**values)
    _check_consistency(path, rec)
    return rec


def _check_consistency(path: Path, rec: RawRecording) -> None:
    if rec.action.ndim != 2 or rec.action.shape[1] != len(rec.actuator_names):
        raise SpecError(path, "action", f"shape [T, {len(rec.actuator_names)}] (one column per actuator)",
                        tuple(rec.action.shape))
    T = rec.num_steps
    if T == 0:
        raise SpecError(path, "action", "at least one control step", "0 steps")
    bad = np.argwhere(~np.isfinite(rec.action))
    if bad.size:
        step, col = bad[0]
        raise SpecError(path, "action", "finite joint targets",
                        f"non-finite value at step {step}, actuator '{rec.actuator_names[col]}'")
    for key in _FINITE:
        bad = np.argwhere(~np.isfinite(getattr(rec, key)))
        if bad.size:
            where = f"at step {bad[0][0]}" if key != "initial_state" else f"at index {bad[0][0]}"
            raise SpecError(path, key, "finite values", f"non-finite value {where}")
    expected = {"robot_qpos": (T, len(rec.robot_joint_names)), "robot_qvel": (T, len(rec.robot_joint_names)),
                "object_pose": (T, len(rec.object_names), 7), "terminal": (T,),
                "stage_latched": (T, len(rec.stage_ids)), "step_flags": (T,)}
    for key, shape in expected.items():
        if getattr(rec, key).shape != shape:
            raise SpecError(path, key, f"shape {shape}", tuple(getattr(rec, key).shape))
    if rec.step_flags.dtype != np.uint8:
        raise SpecError(path, "step_flags", "dtype uint8 (StepFlag bits)", str(rec.step_flags.dtype))
    if len(rec.step_reasons) != T:
        raise SpecError(path, REASONS, f"{T} strings (one per step)", len(rec.step_reasons))
