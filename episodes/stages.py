"""The factory's stages as plain functions over files: raw -> replay -> render -> episode.

Dagster assets and the `b2d` CLI both call these; each writes one file atomically and returns
its metadata. Renders depend only on the replay file and the sensor profile, so a new profile
re-renders without re-simulating the teleop session.
"""

from __future__ import annotations

import json
import logging
import time
from contextlib import closing, nullcontext
from pathlib import Path

import h5py
import numpy as np

from episodes import schema
from episodes.atomic import atomic_path, clean_stale_temporaries, file_sha256, guarded_h5
from episodes.raw import raw_episode_id, read_raw
from episodes.h5_concat import copy_in_name_order
from episodes.replay_frames import ReplayFrames
from episodes.writer import EpisodeWriter
from sim import physics
from sim.errors import SpecError
from sim.registry import SensorProfile
from sim.replay import DEFAULT_DRIFT_BOUND_M, replay

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


def replay_to_file(raw_path: Path, out_path: Path, drift_bound_m: float = DEFAULT_DRIFT_BOUND_M) -> dict:
    """Re-simulate a raw recording; frames whose object drift exceeds `drift_bound_m` are flagged."""
    raw_episode_id(raw_path)            # a foreign file in a folder of recordings is refused
    clean_stale_temporaries(Path(out_path).parent)
    raw = read_raw(raw_path)
    result = replay(raw, source=raw_path, drift_bound_m=drift_bound_m)
    with atomic_path(out_path) as tmp, guarded_h5(tmp) as f:
        f.attrs.update({"schema": REPLAY_SCHEMA, "task": raw.task, "embodiment": raw.embodiment,
                        "episode_id": raw.episode_id, "seed": raw.seed, "scene_sample": raw.scene_sample,
                        "operator": raw.operator, "raw_sha256": file_sha256(raw_path), "hand_model": raw.hand_model,
                        "fidelity": json.dumps(result.fidelity), "episode_metrics": json.dumps(result.episode_metrics),
                        "robot_joint_names": json.dumps(raw.robot_joint_names),
                        "object_names": json.dumps(result.object_names),
                        "articulated_joint_names": json.dumps(result.joint_names),
                        "actuator_names": json.dumps(raw.actuator_names)})
        f.create_dataset("step_flags", data=raw.step_flags, compression="gzip", compression_opts=4)
        f.create_dataset("step_reasons", data=list(raw.step_reasons) or [""] * raw.num_steps, dtype=STR)
        for key in ("qpos", "robot_qpos", "robot_qvel", "robot_qeffort", "object_pose", "object_lin_vel",
                    "object_ang_vel", "joint_qpos", "joint_qvel", "joint_qeffort", "action", "drift_flags"):
            f.create_dataset(key, data=getattr(result, key), compression="gzip", compression_opts=4)
        for key, value in result.traces.items():
            value = np.asarray(value)
            f.create_dataset(f"traces/{key}", data=value if value.dtype.kind not in "UO" else value.astype(STR))
    return {"episode_id": raw.episode_id, "steps": raw.num_steps, "fidelity": result.fidelity,
            "success": bool(result.episode_metrics.get("success", False))}


# ---------------------------------------------------------------- render


def render_to_file(replay_path: Path, profile: SensorProfile, out_path: Path, max_frames: int | None = None,
                   workers: int = 1) -> dict:
    """Render the replay's frames under `profile`. With `workers` > 1 this process renders and writes
    beside `workers` - 1 helper processes (episodes/render_pool.py: started once per process and kept
    across calls) that take frames from a shared counter; the file is byte-identical to one worker's.

    Returns frame counts and `seconds`: time per part of the work (summed over workers), which
    `b2d bench replay` reports."""
    if max_frames is not None and (isinstance(max_frames, bool) or max_frames < 1):
        raise ValueError(f"max_frames: expected a positive number of frames (or None: all), got {max_frames!r}")
    clean_stale_temporaries(Path(out_path).parent)
    with h5py.File(replay_path, "r") as src:
        num_steps = src["qpos"].shape[0]
    steps = frame_steps(num_steps, profile.rate_hz)[:max_frames]
    if not steps.size:
        raise ValueError(f"{replay_path}: no frames to render (max_frames={max_frames})")
    helpers = max(0, min(workers, len(steps) // MIN_FRAMES_PER_WORKER) - 1)
    pool = start_render_helpers(helpers, replay_path) if helpers else None
    if pool is None and len(steps) >= 2 * MIN_FRAMES_PER_WORKER:
        from episodes.render_desk import standby_helpers

        pool = standby_helpers()     # in a batch: its other processes, once they have nothing left to take
        helpers = pool.count if pool is not None else 0
    if pool is not None:
        with pool.job(replay_path, profile, steps, helpers) as job:
            stats = _render_steps(replay_path, profile, steps, out_path, job)
    else:
        stats = _render_steps(replay_path, profile, steps, out_path)
    return {"frames": int(len(steps)), "frame_errors": stats["errors"], "profile": profile.name,
            "profile_hash": profile.content_hash, "workers": stats["workers"], "seconds": stats["seconds"],
            "frame_windows": stats["frame_windows"], "setup_cpu_s": stats["setup_cpu_s"],
            "helper_cpu_s": stats["helper_cpu_s"], "helper_frames": stats["helper_frames"],
            "helper_frames_through_pipe": stats["helper_frames_through_pipe"]}


MIN_FRAMES_PER_WORKER = 8    # below this, a helper's scene and renderer cost more than it saves


def start_render_helpers(count: int, for_path: Path):
    """This process's `count` render helpers (episodes/render_pool.py), started if need be and not
    waited for: a render uses them once they are up. None if they cannot start: then the render runs
    in this process alone, slower but the same bytes."""
    from episodes.render_pool import MAX_HELPERS, shared_helpers

    try:
        return shared_helpers(min(count, MAX_HELPERS), wait=False)
    except (OSError, RuntimeError) as exc:
        log.warning("%s: render helpers did not start (%s); rendering in this process alone", for_path, exc)
        return None


def _render_steps(replay_path: Path, profile: SensorProfile, steps: np.ndarray, out_path: Path, job=None) -> dict:
    """Render the given control steps of a replay into one render file. With `job` (from
    episodes.render_pool) helpers render part of the frames and this process writes them all, in order."""
    clock = time.perf_counter
    t0, cpu0 = clock(), time.process_time()
    frames = ReplayFrames(replay_path, profile, steps)
    seconds = {"setup": clock() - t0, "write": 0.0}
    errors = 0
    try:
        t0 = clock()
        with EpisodeWriter(out_path, frames.static()) as writer:
            writer.file.attrs.update({"schema": RENDER_SCHEMA, "profile": profile.name,
                                      "profile_hash": profile.content_hash})
            seconds["setup"] += clock() - t0     # the file's static datasets: once per file
            setup_cpu = time.process_time() - cpu0   # this process's CPU seconds of the set-up (benchmarks)
            first = time.time()     # wall clock shared by processes: when this part's frames start (benchmarks)
            ordered = job.in_order(frames) if job is not None else map(frames.capture, range(len(steps)))
            with closing(ordered) if job is not None else nullcontext():     # its helpers read to their end
                for frame, error in ordered:
                    errors += error
                    t2 = clock()
                    writer.append(frame)
                    seconds["write"] += clock() - t2
            last = time.time()
            t0 = clock()
        seconds["write"] += clock() - t0    # closing flushes the last chunks
    finally:
        frames.close()
    seconds.update(frames.seconds())
    helped = job.stats if job is not None else []      # each helper's timings, when it took part
    for s in helped:
        for key, value in s["seconds"].items():
            seconds[key] = seconds.get(key, 0.0) + value
    return {"errors": errors, "seconds": seconds, "workers": 1 + sum(bool(s["frame_windows"]) for s in helped),
            "frame_windows": [(first, last)] + [w for s in helped for w in s["frame_windows"]],
            "setup_cpu_s": setup_cpu + sum(s["setup_cpu_s"] for s in helped),
            "helper_cpu_s": sum(s["cpu_s"] for s in helped), "helper_frames": sum(s["frames"] for s in helped),
            "helper_frames_through_pipe": sum(s["frames_through_pipe"] for s in helped)}


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
        joint_names = json.loads(attrs["articulated_joint_names"])
        joints_by_object = _joints_by_object(joint_names)
        success_step = metrics.get("steps_to_stable")   # 1-based count of updates
        drift = rep["drift_flags"][()]
        stream_flags, stream_reasons = _stream_flags_per_frame(rep, steps)
        T = len(steps)
        has_tactile = schema.TACTILE_ROOT in ren
        if profile.tactile_enabled and not has_tactile:
            raise SpecError(render_path, schema.TACTILE_ROOT,
                            f"tactile frames (profile '{profile.name}' enables tactile; re-render)")
        labels = [m for m in schema.LABEL_MODALITIES if m in profile.modalities]
        if labels and schema.LABEL_ID_NODES[0].path not in ren:
            raise SpecError(render_path, "labels", f"label frames (profile '{profile.name}' lists {labels}; re-render)")
        cameras = [m for m in ("rgb", "depth") if m in profile.modalities]    # a policy-input profile may be RGB only
        modalities = cameras + ["robot_state", "object_state"] + (["tactile"] if has_tactile else []) + labels
        static = {
            "meta/task": task.name, "meta/embodiment": attrs["embodiment"], "meta/instruction": task.instruction,
            "meta/scene": attrs["scene_sample"], "meta/modalities": json.dumps(modalities),
            "meta/cameras": json.dumps({cam: {"intrinsic": ren[f"cameras/{cam}/intrinsic"][()].tolist(),
                                              "width": profile.width, "height": profile.height}
                                        for cam in profile.camera_ids}),
            "meta/collection_config": json.dumps({"profile": profile.raw, "profile_hash": profile.content_hash,
                                                  "control_hz": physics.CONTROL_HZ, "substeps": physics.SUBSTEPS,
                                                  "seed": int(attrs["seed"]), "operator": attrs["operator"],
                                                  "hand_model": str(attrs.get("hand_model", "generated"))}),
            "meta/success": np.bool_(metrics.get("success", False)),
            "meta/schema_version": schema.SCHEMA_VERSION,
            "meta/dataset": json.dumps({"producer": "b2d", "episode_id": attrs["episode_id"],
                                        "raw_sha256": attrs["raw_sha256"]}),
            "meta/replay_fidelity": json.dumps(fidelity),
            "action/names": json.loads(attrs["actuator_names"]), "action/source": attrs["operator"],
            "action/control_mode": schema.CONTROL_MODE, "action/action_type": schema.ACTION_TYPE,
            "robot/joint_names": json.loads(attrs["robot_joint_names"]),
            "metrics/episode": json.dumps(metrics, sort_keys=True),
            **{f"objects/{name}/joint_names": [joint_names[c] for c in columns]
               for name, columns in joints_by_object.items()},
        }
        # the replay's per-step arrays, read once (one HDF5 read per frame and field cost ~0.3 ms a frame each)
        rows = {key: rep[key][()] for key in ("action", "robot_qpos", "robot_qvel", "robot_qeffort", "object_pose",
                                              "object_lin_vel", "object_ang_vel", "joint_qpos", "joint_qvel",
                                              "joint_qeffort")}
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
                    "action/action": rows["action"][step], "action/valid": bool(np.isfinite(rows["action"][step]).all()),
                    "action/stream_flags": stream_flags[k], "action/stream_reasons": stream_reasons[k],
                    "frame_valid": not error, "frame_errors": error,
                    "robot/qpos": rows["robot_qpos"][step], "robot/qvel": rows["robot_qvel"][step],
                    "robot/qeffort": rows["robot_qeffort"][step],
                }
                for i, name in enumerate(object_names):
                    frame[f"objects/{name}/pose_world"] = rows["object_pose"][step, i]
                    frame[f"objects/{name}/lin_vel_world"] = rows["object_lin_vel"][step, i]
                    frame[f"objects/{name}/ang_vel_world"] = rows["object_ang_vel"][step, i]
                for name, columns in joints_by_object.items():
                    for key in ("qpos", "qvel", "qeffort"):
                        frame[f"objects/{name}/{key}"] = rows[f"joint_{key}"][step, columns]
                writer.append(frame)
            for cam in profile.camera_ids:
                copy_in_name_order(ren[f"cameras/{cam}"], writer.file, f"cameras/{cam}")
            if has_tactile:
                copy_in_name_order(ren[schema.TACTILE_ROOT], writer.file, schema.TACTILE_ROOT)
            if labels:
                copy_in_name_order(ren["labels"], writer.file, "labels")
            for key, ds in rep["traces"].items():
                writer.file.copy(ds, f"metrics/timeseries/{key}")
            writer.file.create_dataset("metrics/timeseries/sim_step", data=np.arange(1, rep["action"].shape[0] + 1))
    return {"frames": int(T), "success": bool(metrics.get("success", False)), "lscr": metrics.get("lscr"),
            "sha256": file_sha256(out_path), "bytes": out_path.stat().st_size}


def _stream_flags_per_frame(rep: h5py.File, steps: np.ndarray) -> tuple[np.ndarray, list[str]]:
    """The operator stream's flags (StepFlag bits, OR-ed) and distinct reasons over the control steps each
    frame covers, (previous frame's step, this frame's step]; zeros for replays made before they were kept."""
    if "step_flags" not in rep:
        return np.zeros(len(steps), np.uint8), [""] * len(steps)
    flags = rep["step_flags"][()]
    reasons = [r.decode() if isinstance(r, bytes) else str(r) for r in rep["step_reasons"][()]]
    out_flags, out_reasons, start = np.zeros(len(steps), np.uint8), [], 0
    for k, step in enumerate(steps):
        out_flags[k] = np.bitwise_or.reduce(flags[start: step + 1], initial=0)
        lines = [line for r in reasons[start: step + 1] for line in r.splitlines() if line]
        out_reasons.append("\n".join(dict.fromkeys(lines)))
        start = step + 1
    return out_flags, out_reasons


def _joints_by_object(joint_names: list[str]) -> dict[str, list[int]]:
    """Articulated joints ("<object>/<link>") grouped by object: {object: [column, ...]}."""
    groups: dict[str, list[int]] = {}
    for column, joint in enumerate(joint_names):
        groups.setdefault(joint.split("/")[0], []).append(column)
    return groups


def raw_to_episode(raw_path: Path, profile: SensorProfile, out_dir: Path, work_dir: Path | None = None,
                   max_frames: int | None = None, workers: int = 1,
                   drift_bound_m: float = DEFAULT_DRIFT_BOUND_M) -> Path:
    """All three stages for one recording (the `b2d replay` command)."""
    raw_path, out_dir = Path(raw_path), Path(out_dir)
    work = Path(work_dir or out_dir / ".work")
    episode_id = raw_episode_id(raw_path)
    stem = f"episode_{episode_id}"
    out_path = out_dir / schema.episode_filename(episode_id)
    refuse_foreign_episode(out_path, raw_path)      # before the work: the answer does not change
    clean_stale_temporaries(out_dir)
    replay_path = work / f"{stem}.replay.h5"
    render_path = work / f"{stem}.{profile.content_hash}.render.h5"
    if workers > 1:
        start_render_helpers(workers - 1, raw_path)     # they start up while the physics replays
    replay_to_file(raw_path, replay_path, drift_bound_m=drift_bound_m)
    render_to_file(replay_path, profile, render_path, max_frames=max_frames, workers=workers)
    assemble_episode(replay_path, render_path, profile, out_path)
    return out_path


def refuse_foreign_episode(out_path: Path, raw_path: Path) -> None:
    """An episode already at `out_path` is replaced only when it was made from the same recording
    (same raw sha256: a re-run). Two raw files of the same name from different folders replayed into
    one folder overwrote each other silently (issue 23)."""
    if not out_path.exists():
        return
    try:
        with h5py.File(out_path, "r") as f:
            made_from = json.loads(f["meta/dataset"][()]).get("raw_sha256")
    except Exception as exc:
        raise SpecError(out_path, "<file>", "no file, or an episode of this recording (it is replaced); this one "
                                            f"cannot be read ({type(exc).__name__}): move it away or choose another "
                                            "output folder") from None
    if made_from != file_sha256(raw_path):
        raise SpecError(out_path, "meta/dataset", f"no file, or an episode of {raw_path} (it is replaced); this one "
                                                  "was made from another recording of the same name: choose "
                                                  "another output folder or remove it")
