"""The factory's stages as plain functions over files: raw -> replay -> render -> episode.

Dagster assets and the `b2d` CLI both call these; each writes one file atomically and returns
its metadata. Renders depend only on the replay file and the sensor profile, so a new profile
re-renders without re-simulating the teleop session.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import h5py
import mujoco
import numpy as np

from episodes import schema
from episodes.atomic import atomic_path, file_sha256
from episodes.raw import read_raw
from episodes.tactile_frames import TactileFrames
from episodes.writer import EpisodeWriter
from sim import physics
from sim.errors import SpecError
from sim.registry import SensorProfile
from sim.render import CameraRig, set_positions
from sim.replay import replay, scene_for

log = logging.getLogger(__name__)
REPLAY_SCHEMA = "b2d.replay/1"
RENDER_SCHEMA = "b2d.render/1"
STR = h5py.string_dtype()


def frame_steps(num_steps: int, rate_hz: int) -> np.ndarray:
    """Control steps (post-step states) captured at the profile's rate."""
    if physics.CONTROL_HZ % rate_hz:
        raise ValueError(f"sensor rate {rate_hz} Hz must divide the control rate {physics.CONTROL_HZ} Hz")
    stride = physics.CONTROL_HZ // rate_hz
    steps = np.arange(stride - 1, num_steps, stride)
    return steps if steps.size else np.array([num_steps - 1])


# ---------------------------------------------------------------- replay


def replay_to_file(raw_path: Path, out_path: Path) -> dict:
    raw = read_raw(raw_path)
    result = replay(raw, source=raw_path)
    with atomic_path(out_path) as tmp, h5py.File(tmp, "w") as f:
        f.attrs.update({"schema": REPLAY_SCHEMA, "task": raw.task, "embodiment": raw.embodiment,
                        "episode_id": raw.episode_id, "seed": raw.seed, "scene_sample": raw.scene_sample,
                        "operator": raw.operator, "raw_sha256": file_sha256(raw_path),
                        "fidelity": json.dumps(result.fidelity), "episode_metrics": json.dumps(result.episode_metrics),
                        "robot_joint_names": json.dumps(raw.robot_joint_names),
                        "object_names": json.dumps(raw.object_names),
                        "actuator_names": json.dumps(raw.actuator_names)})
        for key in ("qpos", "robot_qpos", "robot_qvel", "robot_qeffort", "object_pose", "object_lin_vel",
                    "object_ang_vel", "action", "drift_flags"):
            f.create_dataset(key, data=getattr(result, key), compression="gzip", compression_opts=4)
        for key, value in result.traces.items():
            value = np.asarray(value)
            f.create_dataset(f"traces/{key}", data=value if value.dtype.kind not in "UO" else value.astype(STR))
    return {"episode_id": raw.episode_id, "steps": raw.num_steps, "fidelity": result.fidelity,
            "success": bool(result.episode_metrics.get("success", False))}


# ---------------------------------------------------------------- render


def render_to_file(replay_path: Path, profile: SensorProfile, out_path: Path, max_frames: int | None = None) -> dict:
    with h5py.File(replay_path, "r") as src:
        raw_like = _RawView(src)
        qpos = src["qpos"][()]
    scene = scene_for(raw_like, replay_path)
    model = scene.model
    data = mujoco.MjData(model)
    steps = frame_steps(qpos.shape[0], profile.rate_hz)[:max_frames]
    rig = CameraRig(model, profile)
    static = {f"cameras/{cam}/intrinsic": K for cam, K in rig.intrinsics().items()}
    for cam in profile.camera_ids:
        static[f"cameras/{cam}/camera_model"] = schema.CAMERA_MODEL
        static[f"cameras/{cam}/depth_semantics"] = schema.DEPTH_SEMANTICS
        static[f"cameras/{cam}/clip_range_m"] = np.array([profile.clip_near_m, profile.clip_far_m])
    static["render/frame_steps"] = steps
    tactile = TactileFrames(scene, profile) if profile.tactile_enabled else None
    if tactile is not None:   # tactile comes from the same posed state as the images (paper: same pass)
        static.update(tactile.static())
    errors = 0
    with EpisodeWriter(out_path, static) as writer:
        writer.file.attrs.update({"schema": RENDER_SCHEMA, "profile": profile.name,
                                  "profile_hash": profile.content_hash})
        for step in steps:
            set_positions(model, data, qpos[step])
            frame, error = {}, ""
            try:
                shots = rig.capture(data)
            except Exception as exc:   # keep the episode: flag the frame instead of aborting
                error, shots = f"render failed: {exc}", _blank_shots(profile)
            for cam, T in rig.extrinsics(data).items():
                frame[f"cameras/{cam}/extrinsic_world_from_cam"] = T
                for key, img in shots[cam].items():
                    frame[f"cameras/{cam}/{key}"] = img
            if tactile is not None:
                touch, touch_error = tactile.capture(data)
                frame.update(touch)
                error = "; ".join(e for e in (error, touch_error) if e)
            errors += bool(error)
            frame["render/frame_errors"] = error
            writer.append(frame)
    rig.close()
    return {"frames": int(len(steps)), "frame_errors": errors, "profile": profile.name,
            "profile_hash": profile.content_hash}


def _blank_shots(profile: SensorProfile) -> dict:
    h, w = profile.height, profile.width
    return {cam: {"rgb": np.zeros((h, w, 3), np.uint8), "depth_m": np.zeros((h, w), np.float32)}
            for cam in profile.camera_ids}


class _RawView:
    """The fields of a raw recording that `scene_for` needs, read from a replay file."""

    def __init__(self, f: h5py.File):
        self.task = f.attrs["task"]
        self.embodiment = f.attrs["embodiment"]
        self.scene_sample = f.attrs["scene_sample"]
        self.actuator_names = json.loads(f.attrs["actuator_names"])


# ---------------------------------------------------------------- assemble


def assemble_episode(replay_path: Path, render_path: Path, profile: SensorProfile, out_path: Path) -> dict:
    """Write the paper's per-episode layout from a replay and a render, frame by frame."""
    from sim.tasks import load_task

    with h5py.File(replay_path, "r") as rep, h5py.File(render_path, "r") as ren:
        attrs = dict(rep.attrs)
        task = load_task(attrs["task"])
        steps = ren["render/frame_steps"][()]
        render_errors = ren["render/frame_errors"][()]
        metrics = json.loads(attrs["episode_metrics"])
        fidelity = json.loads(attrs["fidelity"])
        object_names = json.loads(attrs["object_names"])
        success_step = metrics.get("steps_to_stable")   # 1-based count of updates
        drift = rep["drift_flags"][()]
        T = len(steps)
        has_tactile = schema.TACTILE_ROOT in ren
        if profile.tactile_enabled and not has_tactile:
            raise SpecError(render_path, schema.TACTILE_ROOT,
                            f"tactile frames (profile '{profile.name}' enables tactile; re-render)")
        modalities = ["rgb", "depth", "robot_state", "object_state"] + (["tactile"] if has_tactile else [])
        static = {
            "meta/task": task.name, "meta/embodiment": attrs["embodiment"], "meta/instruction": task.instruction,
            "meta/scene": attrs["scene_sample"], "meta/modalities": json.dumps(modalities),
            "meta/cameras": json.dumps({cam: {"intrinsic": ren[f"cameras/{cam}/intrinsic"][()].tolist(),
                                              "width": profile.width, "height": profile.height}
                                        for cam in profile.camera_ids}),
            "meta/collection_config": json.dumps({"profile": profile.raw, "profile_hash": profile.content_hash,
                                                  "control_hz": physics.CONTROL_HZ, "substeps": physics.SUBSTEPS,
                                                  "seed": int(attrs["seed"]), "operator": attrs["operator"]}),
            "meta/success": np.bool_(metrics.get("success", False)),
            "meta/schema_version": schema.SCHEMA_VERSION,
            "meta/dataset": json.dumps({"producer": "b2d", "episode_id": attrs["episode_id"],
                                        "raw_sha256": attrs["raw_sha256"]}),
            "meta/replay_fidelity": json.dumps(fidelity),
            "action/names": json.loads(attrs["actuator_names"]), "action/source": attrs["operator"],
            "action/control_mode": schema.CONTROL_MODE, "action/action_type": schema.ACTION_TYPE,
            "robot/joint_names": json.loads(attrs["robot_joint_names"]),
            "metrics/episode": json.dumps(metrics, sort_keys=True),
        }
        with EpisodeWriter(out_path, static) as writer:
            for k, step in enumerate(steps):
                error = render_errors[k].decode() if isinstance(render_errors[k], bytes) else str(render_errors[k])
                if drift[step]:
                    error = (error + "; " if error else "") + "replay drift beyond bound"
                frame = {
                    "time/frame_index": np.int64(k), "time/sim_step": np.int64(step + 1),
                    "time/timestamp_ns": np.int64((step + 1) * 1_000_000_000 // physics.CONTROL_HZ),
                    "episode/is_first": k == 0, "episode/is_last": k == T - 1, "episode/done": k == T - 1,
                    "episode/success": success_step is not None and step + 1 >= success_step,
                    "action/action": rep["action"][step], "action/valid": bool(np.isfinite(rep["action"][step]).all()),
                    "frame_valid": not error, "frame_errors": error,
                    "robot/qpos": rep["robot_qpos"][step], "robot/qvel": rep["robot_qvel"][step],
                    "robot/qeffort": rep["robot_qeffort"][step],
                }
                for i, name in enumerate(object_names):
                    frame[f"objects/{name}/pose_world"] = rep["object_pose"][step, i]
                    frame[f"objects/{name}/lin_vel_world"] = rep["object_lin_vel"][step, i]
                    frame[f"objects/{name}/ang_vel_world"] = rep["object_ang_vel"][step, i]
                writer.append(frame)
            for cam in profile.camera_ids:
                writer.file.copy(ren[f"cameras/{cam}"], f"cameras/{cam}")
            if has_tactile:
                writer.file.copy(ren[schema.TACTILE_ROOT], schema.TACTILE_ROOT)
            for key, ds in rep["traces"].items():
                writer.file.copy(ds, f"metrics/timeseries/{key}")
            writer.file.create_dataset("metrics/timeseries/sim_step", data=np.arange(1, rep["action"].shape[0] + 1))
    return {"frames": int(T), "success": bool(metrics.get("success", False)), "lscr": metrics.get("lscr"),
            "sha256": file_sha256(out_path), "bytes": out_path.stat().st_size}


def raw_to_episode(raw_path: Path, profile: SensorProfile, out_dir: Path, work_dir: Path | None = None,
                   max_frames: int | None = None) -> Path:
    """All three stages for one recording (the `b2d replay` command)."""
    raw_path, out_dir = Path(raw_path), Path(out_dir)
    work = Path(work_dir or out_dir / ".work")
    stem = raw_path.name.removesuffix(".raw.h5")
    replay_path = work / f"{stem}.replay.h5"
    render_path = work / f"{stem}.{profile.content_hash}.render.h5"
    replay_to_file(raw_path, replay_path)
    render_to_file(replay_path, profile, render_path, max_frames=max_frames)
    episode_id = stem.removeprefix("episode_")
    out_path = out_dir / schema.episode_filename(episode_id)
    assemble_episode(replay_path, render_path, profile, out_path)
    return out_path
