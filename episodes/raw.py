"""Raw recordings: the lightweight motion stream written while an operator drives the robot.

One HDF5 file per episode holding what replay needs to reproduce it exactly: the full MuJoCo
integration state after homing, the seed and resolved scene sample, and per control step the action
executed next followed by the post-step robot/object state and the evaluator state (paper:
"Online Teleoperation Setup"). Reading validates everything and names the file and field at fault.

Per step, ``step_flags`` holds the operator stream's ``StepFlag`` bits (teleop/streams/sanitizer.py:
dropped or out-of-order frames, non-finite keypoints, bad or unreachable wrist poses; 0 = clean) and
the optional ``step_reasons`` dataset the same steps' reasons as text, one per line ("" = clean).
Files written before ``step_reasons`` existed read with every reason "".

Recordings driven by an operator stream (``b2d record --operator stream``, ``b2d teleop``) also keep
that stream in the optional ``operator_stream`` group (``OperatorStreamRecord``): per control step the
frame that reached the sanitizer (``arrived`` False: none did), both hands' keypoints in the stream's
wrist frame, wrist poses, their validity, and the step's time on the stream's clock, plus as a JSON
attribute the settings that turned it into commands (sanitizer period, translation scale, DexPilot
configuration). `b2d retarget` feeds it through another embodiment's retargeting. Files without the
group (the direct joint path, files written before it existed) read with ``stream = None``.
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
from sim.embodiment.retarget_spec import MEDIAPIPE_KEYPOINTS
from sim.errors import SpecError

RAW_SCHEMA = "b2d.raw/1"
RAW_NAME = re.compile(r"episode_(\d+)\.raw\.h5")


STREAM = "operator_stream"     # optional group
# per-step stream datasets: name -> (shape after T, accepted dtype kind, dtype written)
STREAM_FIELDS = {
    "arrived": ((), "b", np.bool_),                                    # a frame reached the sanitizer
    "timestamp_ns": ((), "i", np.int64),                               # its timestamp (stream clock)
    "keypoints": ((2, len(MEDIAPIPE_KEYPOINTS), 3), "f", np.float64),  # left, right; wrist frame, as arrived
    "wrist_pos": ((2, 3), "f", np.float64),                            # tracker frame
    "wrist_quat": ((2, 4), "f", np.float64),                           # w x y z
    "keypoints_valid": ((2,), "b", np.bool_),
    "wrist_valid": ((2,), "b", np.bool_),
    "clock_ns": ((), "i", np.int64),         # the step's time on the stream's clock, given to the sanitizer
    "clock_known": ((), "b", np.bool_),      # False: no clock yet (a live device before its first frame)
}
STREAM_SETTINGS = "settings"     # JSON attribute of the group
STREAM_SETTING_KEYS = {"nominal_period_ns": (int, type(None)), "translation_scale": (int, float), "retarget": (dict,)}


@dataclass
class OperatorStreamRecord:
    """The operator stream that produced a recording's actions, one row per control step (frames are
    stored as they arrived, bad ones included, so the sanitizer decides the same way again)."""

    arrived: np.ndarray
    timestamp_ns: np.ndarray
    keypoints: np.ndarray
    wrist_pos: np.ndarray
    wrist_quat: np.ndarray
    keypoints_valid: np.ndarray
    wrist_valid: np.ndarray
    clock_ns: np.ndarray
    clock_known: np.ndarray
    settings: dict      # {"nominal_period_ns": int | None, "translation_scale": float, "retarget": {DexPilot}}

    @property
    def num_steps(self) -> int:
        return int(self.arrived.shape[0])


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
    stream: OperatorStreamRecord | None = None   # the operator stream behind the actions, when there was one

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
        if rec.stream is not None:
            group = f.create_group(STREAM)
            group.attrs[STREAM_SETTINGS] = json.dumps(rec.stream.settings, sort_keys=True)
            for key, (_, _, dtype) in STREAM_FIELDS.items():
                group.create_dataset(key, data=np.asarray(getattr(rec.stream, key), dtype=dtype),
                                     compression="gzip", compression_opts=4)
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
    values["stream"] = _read_stream(path, f) if STREAM in f else None
    return values


def _read_stream(path: Path, f: h5py.File) -> OperatorStreamRecord:
    group = f[STREAM]
    if not isinstance(group, h5py.Group):
        raise SpecError(path, STREAM, "a group of per-step operator stream datasets", f"a {type(group).__name__}")
    values = {}
    for key, (shape, kind, dtype) in STREAM_FIELDS.items():
        where = f"{STREAM}/{key}"
        if key not in group or not isinstance(group[key], h5py.Dataset):
            raise SpecError(path, where, f"a dataset of shape {('T', *shape)} (one row per control step)")
        try:
            values[key] = group[key][()]
        except (OSError, ValueError, TypeError) as exc:
            raise SpecError(path, where, "readable data (file is truncated or corrupt)") from exc
        if np.asarray(values[key]).dtype.kind != kind:
            raise SpecError(path, where, f"a dataset of dtype {np.dtype(dtype).name}",
                            str(np.asarray(values[key]).dtype))
    if STREAM_SETTINGS not in group.attrs:
        raise SpecError(path, f"{STREAM}/{STREAM_SETTINGS}",
                        "a JSON object attribute (sanitizer and retargeting settings)")
    try:
        settings = _json_attr(path, group, STREAM_SETTINGS, "", dict)
    except SpecError as exc:       # name the attribute with its group
        raise SpecError(path, f"{STREAM}/{STREAM_SETTINGS}", exc.expected) from None
    for key, types in STREAM_SETTING_KEYS.items():
        value = settings.get(key, ...)
        if not isinstance(value, types) or isinstance(value, bool):
            raise SpecError(path, f"{STREAM}/{STREAM_SETTINGS}", f"a JSON object with '{key}' of type "
                            f"{' or '.join(t.__name__ for t in types)}", settings.get(key))
    anchors = settings.get("wrist_anchors", {})       # optional: preset wrist anchors (b2d retarget --wrist world)
    if not (isinstance(anchors, dict) and set(anchors) <= {"left", "right"} and all(
            isinstance(v, list) and len(v) == 7 and all(isinstance(x, (int, float)) and np.isfinite(x) for x in v)
            for v in anchors.values())):
        raise SpecError(path, f"{STREAM}/{STREAM_SETTINGS}", "'wrist_anchors', when given, as {side: [x, y, z, qw, "
                        "qx, qy, qz]} for sides left and right", anchors)
    return OperatorStreamRecord(**values, settings=settings)


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
    if rec.stream is not None:
        for key, (shape, _, _) in STREAM_FIELDS.items():
            got = np.shape(getattr(rec.stream, key))
            if got != (T, *shape):
                raise SpecError(path, f"{STREAM}/{key}", f"shape {(T, *shape)} (one row per control step)", got)
