"""Benchmarks that print figures (`b2d bench recorder|replay|tactile-replay`), with baselines from the
same run."""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

from episodes.stages import assemble_episode, render_to_file, replay_to_file
from sim import physics
from sim.registry import sensor_profile
from sim.render import MUJOCO_TESSELLATION
from sim.scene.builder import demonstration_scene
from sim.scene.state import SceneObserver
from teleop.demos import record_demonstrations
from teleop.recorder import home, new_buffer, store_step
from teleop.scripted_operator import ScriptedOperator

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"
TACTILE_BENCH_MIN_STEPS = 480  # long enough for the scripted operator's first grasp


def _scene():
    return demonstration_scene(TASK, EMBODIMENT)


def _stream_inputs(scene, data, steps: int) -> list:
    """The scripted person's stream input of each step (frame and clock), as a stream recording keeps it."""
    from teleop.scripted_stream import ScriptedStreamOperator

    op = ScriptedStreamOperator()
    op.reset(scene, data)
    return [(op.act(t, data), op.stream_step)[1] for t in range(steps)]


def bench_recorder(steps: int) -> dict:
    """Per control step, in one run on the same trajectory: physics alone (`physics.step_control`, the
    baseline), one MuJoCo step (`mj_step`), the recording (the buffer store: action, robot and object
    state, evaluator state, straight from MjData) and the evaluation (the scene snapshot the evaluator
    reads + its update), which any online session runs, recorded or not: it decides success and the
    reach-and-stop. Even steps time `step_control`, odd steps its SUBSTEPS `mj_step` calls one by one (the same
    physics), so both baselines come from this trajectory. Times are this thread's CPU time, less the
    clock's own cost, so other processes on shared cores do not count as overhead."""
    import mujoco

    from evaluation.evaluator import EpisodeEvaluator

    scene = _scene()
    model, data = scene.model, home(scene)
    op = ScriptedOperator()
    op.reset(scene, data)
    actions = [op.act(t, data) for t in range(steps)]        # operator cost is not the recorder's
    streams = _stream_inputs(scene, data, steps)              # a stream operator's per-step input
    observer = SceneObserver(scene)
    evaluator = EpisodeEvaluator(scene.task.metrics, observer.context)
    buf = new_buffer(scene, len(evaluator.stage_ids))
    stream_buf = new_buffer(scene, len(evaluator.stage_ids), stream=True)
    stream_store_s = []
    clock = time.thread_time
    tick = min(-clock() + clock() for _ in range(1000))      # an empty interval: the clock's own cost
    control_s, mj_step_s, snapshot_s, store_s, evaluator_s = [], [], [], [], []
    for t in range(steps):      # the calls of teleop.recorder.record_step, timed one by one
        t0 = clock()
        if t % 2 == 0:
            physics.step_control(model, data, actions[t])
            control_s.append(clock() - t0 - tick)
        else:
            data.ctrl[:] = actions[t]
            for _ in range(physics.SUBSTEPS):
                t0 = clock()
                mujoco.mj_step(model, data)
                mj_step_s.append(clock() - t0 - tick)
        t1 = clock()
        state = observer.state(data)
        t2 = clock()
        record = evaluator.update(state, physics.CONTROL_DT)
        t3 = clock()
        if t % 2:       # the same step also into a buffer with the stream's rows, first on every other step
            t5 = clock()
            store_step(observer, stream_buf, data, actions[t], record, stream=streams[t])
            stream_store_s.append(clock() - t5 - tick)
        t6 = clock()
        store_step(observer, buf, data, actions[t], record)
        t4 = clock()
        if t % 2 == 0:
            t5 = clock()
            store_step(observer, stream_buf, data, actions[t], record, stream=streams[t])
            stream_store_s.append(clock() - t5 - tick)
        snapshot_s.append(t2 - t1 - tick)
        evaluator_s.append(t3 - t2 - tick)
        store_s.append(t4 - t6 - tick)
    parts = {"physics_control_step": control_s, "physics_mj_step": mj_step_s, "recording": store_s,
             "evaluation": np.add(snapshot_s, evaluator_s), "evaluation_snapshot": snapshot_s,
             "evaluation_update": evaluator_s, "recording_with_stream": stream_store_s}
    mean = {k: 1e3 * float(np.mean(v)) for k, v in parts.items()}
    median = {k: 1e3 * float(np.median(v)) for k, v in parts.items()}
    recording, control, evaluation = mean["recording"], mean["physics_control_step"], mean["evaluation"]
    return {
        "task": TASK, "embodiment": EMBODIMENT, "steps": steps, "substeps_per_control_step": physics.SUBSTEPS,
        "ms_per_control_step": {k: round(v, 4) for k, v in mean.items()},
        "median_ms_per_control_step": {k: round(v, 4) for k, v in median.items()},
        "recording_vs_control_step": round(recording / control, 4),
        "recording_vs_mj_step": round(recording / mean["physics_mj_step"], 4),
        "recording_with_stream_vs_recording": round(mean["recording_with_stream"] / recording, 4),
        "recording_with_stream_vs_control_step": round(mean["recording_with_stream"] / control, 4),
        "evaluation_vs_control_step": round(evaluation / control, 4),
        "recording_plus_evaluation_vs_control_step": round((recording + evaluation) / control, 4),
        "load_average_1min": round(os.getloadavg()[0], 2),
        "note": (f"means (ratios) and medians over the steps of this thread's CPU time; a control step (1/"
                 f"{physics.CONTROL_HZ} s) is {physics.SUBSTEPS} mj_step physics steps of {1e3 * physics.TIMESTEP:.3f} ms "
                 "simulated time (the teleop loop's physics step is the control step); recording = the buffer "
                 "store (goal: under 5% of a physics step); evaluation = snapshot + update, which every online "
                 "session runs, recorded or not, so it has its own lines"),
    }


def bench_replay(profile_name: str, steps: int, workers: int = 1, setting: str | None = None) -> dict:
    """Frames per second per core through replay -> render -> assemble, the share of time in each
    part of the work (physics, each camera modality, tactile, posing, writing), bytes per frame on
    disk per modality; with `workers` > 1 also the render's speed-up over one worker. `steps` 0 records a
    whole demonstration (until the scripted operator's plan ends); `setting` (a key) replaces the foundation's.
    OpenCV (segment lookups, the tactile blur) runs on one thread meanwhile, as the figures are per core."""
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        return _bench_replay(profile_name, steps, workers, setting)
    finally:
        cv2.setNumThreads(threads)


def _bench_replay(profile_name: str, steps: int, workers: int, setting: str | None = None) -> dict:
    from sim.registry import parse_setting_key

    profile = sensor_profile(profile_name)
    chosen = parse_setting_key(setting or f"{TASK}__{EMBODIMENT}")
    task, embodiment = chosen.task, chosen.embodiment
    clock = time.perf_counter
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        recorded = record_demonstrations(task, embodiment, 1, tmp, max_steps=steps or None)[0]
        if recorded.path is None:
            raise RuntimeError(f"{task} on {embodiment}: the demonstration failed to record: {recorded.error}")
        raw, steps = recorded.path, recorded.steps
        cpu0 = time.process_time()      # every thread of this process
        t0 = clock()
        replay_to_file(raw, tmp / "e.replay.h5")
        t1 = clock()
        replay_cpu = time.process_time() - cpu0
        info = render_to_file(tmp / "e.replay.h5", profile, tmp / "e.render.h5")
        t2 = clock()
        out = assemble_episode(tmp / "e.replay.h5", tmp / "e.render.h5", profile, tmp / "episode_e.hdf5")
        t3 = clock()
        cpu = time.process_time() - cpu0
        stored = _bytes_by_modality(tmp / "episode_e.hdf5")
        parallel = {}
        if workers > 1:
            from b2d_cli.render_workers_bench import (batch_figures, cold_start_figures, parallel_render_figures,
                                                      side_by_side_figures)
            parallel = parallel_render_figures(tmp / "e.replay.h5", profile, workers, tmp)
            parallel["independent_renders_side_by_side"] = side_by_side_figures(tmp / "e.replay.h5", profile,
                                                                                workers, tmp)
            parallel["speedup_share_of_ceiling"] = round(
                parallel["speedup_vs_one_worker"] / parallel["independent_renders_side_by_side"]["ceiling_speedup"], 3)
            parallel["one_file_in_a_fresh_process"] = cold_start_figures(raw, profile, workers, tmp)
            parallel["a_batch_of_recordings"] = batch_figures(raw, profile, workers, tmp)
        comparison = _tessellation_comparison(tmp / "e.replay.h5", profile) if profile.tessellation else {}
        layers = _still_layer_comparison(tmp / "e.replay.h5", profile)
        setup_ways = _renderer_setup_comparison(task, embodiment, profile)
    frames, total = info["frames"], t3 - t0
    cpu_per_frame = max(cpu - info["setup_cpu_s"], 1e-9) / frames
    whole_per_frame = cpu_per_frame + (layers["camera_cpu_ms_per_frame_whole_passes"]
                                       - layers["camera_cpu_ms_per_frame"]) / 1e3
    layers["frames_per_cpu_second_whole_passes"] = round(1 / whole_per_frame, 3)
    layers["frames_per_cpu_second_speedup"] = round(whole_per_frame / cpu_per_frame, 3)
    seconds = dict(info["seconds"])
    setup = seconds.pop("setup", 0.0)       # once per render file: reported apart, not spread over frames
    per_frame = total - setup
    parts = {"physics_replay": t1 - t0, **{f"render_{k}": v for k, v in seconds.items()},
             "assemble_write": t3 - t2}
    parts["render_other"] = max(0.0, (t2 - t1) - setup - sum(seconds.values()))
    unavoidable = sum(v for k, v in seconds.items() if k in UNAVOIDABLE_RENDER_PARTS)
    return {"profile": profile_name, "setting": chosen.key, "control_steps": steps, "frames": frames,
            "cameras": len(profile.camera_ids), "resolution": [profile.width, profile.height],
            "tactile_sites": "on" if profile.tactile_enabled else "off",
            "shadows": profile.shadows, "antialias": profile.antialias,
            "frames_per_second_per_core": round(frames / per_frame, 3),
            "frames_per_second_per_core_with_setup": round(frames / total, 3),
            # the same from this process's CPU time: what a frame costs a core even when other processes
            # share the cores (wall-clock figures then count their time too)
            "frames_per_cpu_second": round(frames / max(cpu - info["setup_cpu_s"], 1e-9), 3),
            # a re-render under another sensor profile: the replay stays on disk, only render + assemble run
            "re_render_frames_per_cpu_second": round(frames / max(cpu - replay_cpu - info["setup_cpu_s"], 1e-9), 3),
            "seconds": round(total, 3),
            "cpu_seconds_per_wall_second": round(cpu / total, 3),
            "llvmpipe_threads": os.environ.get("LP_NUM_THREADS", "one per core (Mesa's default)"),
            "opencv_threads": cv2.getNumThreads(),
            "share": {k: round(v / per_frame, 4) for k, v in parts.items()},
            "ms_per_frame": {k: round(1e3 * v / max(frames, 1), 3) for k, v in parts.items()},
            "unavoidable_render_and_raycast_share": round(unavoidable / per_frame, 4),
            "unavoidable_share_with_setup_spread_over_these_frames": round(unavoidable / total, 4),
            "one_off_per_render_file_ms": {"render_setup": round(1e3 * setup, 1)},
            "bytes_per_frame_on_disk": round(out["bytes"] / max(frames, 1)),
            "bytes_per_frame_by_modality": {k: round(v / max(frames, 1)) for k, v in stored.items()},
            **({"parallel_render": parallel} if parallel else {}),
            **({"tessellation_vs_mujoco_default": comparison} if comparison else {}),
            "still_layers_vs_whole_passes": layers,
            "renderer_setup_now_vs_before": setup_ways,
            "load_average_1min": round(os.getloadavg()[0], 2),
            "note": (f"scripted {task} on {embodiment}, one core (cpu_seconds_per_wall_second ~1: no other thread "
                     "worked; llvmpipe_threads 0 = software GL on the calling thread); shares and ms_per_frame are the run's time "
                     "less the render set-up, so the replay's and the assembly's own one-off costs (scene build, "
                     "opening files) are still in physics_replay and assemble_write; render_setup (scene build, label and tactile set-up, once per render file) is "
                     "reported apart in one_off_per_render_file_ms and, spread over this run's frames, in the "
                     "_with_setup figures; unavoidable = the GL render and read-back of each camera pass and "
                     "tactile ray casting; camera_decode (GL buffers -> metric depth and geom ids) is CPU work "
                     "counted as overhead; physics_replay includes the evaluator")}


def _cameras_two_ways(replay_path: Path, profile, make_rigs, compare) -> tuple[dict, int]:
    """Every frame of a replay captured by two camera rigs in turn, on the same poses, alternating which
    goes first (so both see the same load): this thread's CPU seconds per rig (all of the GL work when
    LP_NUM_THREADS=0, as b2d bench sets it) and the number of frames. ``make_rigs(model)`` gives the two
    rigs by name; ``compare(shots)`` sees each frame's captures by rig name."""
    import h5py
    import mujoco

    from episodes.replay_frames import RawView
    from episodes.stages import frame_steps
    from sim.render import set_positions
    from sim.replay import scene_for

    with h5py.File(replay_path, "r") as src:
        scene = scene_for(RawView(src), replay_path)
        qpos = src["qpos"][()]
    model, data = scene.model, mujoco.MjData(scene.model)
    rigs = make_rigs(model)
    names = list(rigs)
    cpu = {k: 0.0 for k in rigs}
    steps = frame_steps(len(qpos), profile.rate_hz)
    try:
        for k, step in enumerate(steps):
            set_positions(model, data, qpos[step])
            shots = {}
            for name in (names if k % 2 == 0 else names[::-1]):
                t0 = time.thread_time()
                shots[name] = rigs[name].capture(data)
                cpu[name] += time.thread_time() - t0
            compare(shots)
    finally:
        for rig in rigs.values():
            rig.close()
    return cpu, len(steps)


def _tessellation_comparison(replay_path: Path, profile) -> dict:
    """The cameras of a profile that sets its own tessellation against the same profile at MuJoCo's default
    (what it rendered before it had one), frame by frame on the same poses, alternating (so both see the
    same load): this thread's CPU time per frame and the share of pixels that differ."""
    import dataclasses

    from sim.render import CameraRig

    default = dataclasses.replace(profile, tessellation=None)
    rgb_changed, depth_changed = [], []

    def compare(shots: dict) -> None:
        for cam, shot in shots["profile"].items():
            ref = shots["mujoco_default"][cam]
            if "rgb" in shot:
                rgb_changed.append(float((shot["rgb"] != ref["rgb"]).any(axis=-1).mean()))
            if "depth_m" in shot:
                depth_changed.append(float((np.abs(shot["depth_m"] - ref["depth_m"]) > 0.002).mean()))

    cpu, frames = _cameras_two_ways(
        replay_path, profile,
        lambda model: {"profile": CameraRig(model, profile), "mujoco_default": CameraRig(model, default)}, compare)
    return {"tessellation": list(profile.tessellation), "mujoco_default": list(MUJOCO_TESSELLATION),
            "camera_cpu_ms_per_frame": round(1e3 * cpu["profile"] / frames, 3),
            "camera_cpu_ms_per_frame_mujoco_default": round(1e3 * cpu["mujoco_default"] / frames, 3),
            "camera_speedup": round(cpu["mujoco_default"] / max(cpu["profile"], 1e-9), 3),
            "rgb_pixels_changed": round(float(np.mean(rgb_changed)), 4) if rgb_changed else None,
            "depth_pixels_changed_over_2mm": round(float(np.mean(depth_changed)), 4) if depth_changed else None,
            "note": "every camera of every frame rendered both ways in turn; CPU time of this thread (all of the "
                    "GL work when LP_NUM_THREADS=0, as b2d bench sets it)"}


def _still_layer_comparison(replay_path: Path, profile) -> dict:
    """The cameras of a profile with the still cameras' kept layers of the welded geoms (sim.offscreen, the
    render stage's way) against every pass rendered whole (the code before them), frame by frame on the
    same poses, alternating which goes first: this thread's CPU time per frame and whether every image
    is byte-identical."""
    from sim.render import CameraRig
    from sim.still_layers import still_cameras, welded_bodies

    segments = any(m in profile.modalities for m in ("segmentation", "box2d"))
    identical, still = [True], []

    def make_rigs(model) -> dict:
        still.extend(sorted(model.camera(i).name for i in still_cameras(model, welded_bodies(model))
                            if model.camera(i).name in profile.camera_ids))
        return {"layers": CameraRig(model, profile, segments=segments),
                "whole": CameraRig(model, profile, segments=segments, still_layers=False)}

    def compare(shots: dict) -> None:
        for cam, shot in shots["whole"].items():
            other = shots["layers"][cam]
            for key, image in shot.items():
                a, b = (image.index, other[key].index) if key == "segments" else (image, other[key])
                identical[0] &= a.tobytes() == b.tobytes()

    cpu, frames = _cameras_two_ways(replay_path, profile, make_rigs, compare)
    return {"still_cameras": still,
            "camera_cpu_ms_per_frame": round(1e3 * cpu["layers"] / frames, 3),
            "camera_cpu_ms_per_frame_whole_passes": round(1e3 * cpu["whole"] / frames, 3),
            "camera_speedup": round(cpu["whole"] / max(cpu["layers"], 1e-9), 3),
            "images_identical": bool(identical[0]),
            "note": "every camera of every frame rendered both ways in turn (CPU time of this thread); "
                    "frames_per_cpu_second_whole_passes = this run's frames_per_cpu_second with the "
                    "camera time of whole passes instead (the code before the layers), and _speedup the ratio"}


def _renderer_setup_comparison(task: str, embodiment: str, profile, rounds: int = 5) -> dict:
    """A camera renderer's GL set-up, paid once per render file and per rollout: the render stage's way
    (the thread's shared GL context, no shadow map without shadows) against the code before (a fresh GL
    context per renderer and MuJoCo's default context with its shadow map), alternating; CPU time of the
    process, so llvmpipe's own threads count too."""
    import mujoco

    from sim.offscreen import OffscreenRenderer, gl_context_class
    from sim.render import apply_antialias, apply_tessellation

    model = demonstration_scene(task, embodiment).model
    apply_antialias(model, profile)
    apply_tessellation(model, profile)

    def before() -> None:
        gl = gl_context_class()(profile.width, profile.height)
        gl.make_current()
        mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150).free()
        gl.free()

    ways = {"before": before,
            "now": lambda: OffscreenRenderer(model, profile.width, profile.height, shadows=profile.shadows).close()}
    ways["now"]()       # the thread's GL context, made once per process
    cpu = dict.fromkeys(ways, 0.0)
    for _ in range(rounds):
        for name, make in ways.items():
            c0 = time.process_time()
            make()
            cpu[name] += time.process_time() - c0
    return {"cpu_ms_now": round(1e3 * cpu["now"] / rounds, 2),
            "cpu_ms_before": round(1e3 * cpu["before"] / rounds, 2),
            "speedup": round(cpu["before"] / max(cpu["now"], 1e-9), 2),
            "note": f"{rounds} renderers made and closed each way, alternating; now = sim.offscreen "
                    "(the thread's shared GL context, no shadow map unless the profile has shadows); before "
                    "= a fresh GL context and MuJoCo's default context per renderer (its "
                    f"{int(model.vis.quality.shadowsize)}-square shadow map made whether or not a scene asks)"}


# Render parts that are the sensors' own work (everything else is overhead the factory adds).
UNAVOIDABLE_RENDER_PARTS = ("camera_rgb", "camera_depth_and_ids", "tactile")


def _bytes_by_modality(path: Path) -> dict[str, int]:
    """Stored (compressed) bytes per modality of an episode file."""
    import h5py

    sizes: dict[str, int] = {}

    def add(name, obj) -> None:
        if isinstance(obj, h5py.Dataset):
            top = name.split("/")
            key = top[-1] if top[0] == "cameras" else "tactile" if name.startswith("robot/tactile") else top[0]
            sizes[key] = sizes.get(key, 0) + obj.id.get_storage_size()

    with h5py.File(path) as f:
        f.visititems(add)
    return dict(sorted(sizes.items()))


def _mean_ms(seconds: list[float]) -> float:
    return round(1e3 * float(np.mean(seconds)), 3) if seconds else 0.0


def bench_tactile_replay(profile_name: str, steps: int) -> dict:
    """Added cost of tactile per rendered frame, against the cameras of the same frames (same run).

    Per frame: pose the replayed state, render every camera of the profile, then sense every
    tactile site and append its datasets to an HDF5 file (what `render_to_file` adds per frame).
    """
    import mujoco

    from episodes.raw import read_raw
    from episodes.stages import frame_steps
    from episodes.tactile_frames import TactileFrames, frame_datasets
    from episodes.writer import EpisodeWriter
    from sim.render import CameraRig, set_positions
    from sim.replay import replay, scene_for

    profile = sensor_profile(profile_name)
    if not profile.tactile_enabled:
        raise ValueError(f"sensor profile '{profile_name}' disables tactile: nothing to measure")
    steps = max(steps, TACTILE_BENCH_MIN_STEPS)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        raw = read_raw(record_demonstrations(TASK, EMBODIMENT, 1, tmp, max_steps=steps)[0].path)
        qpos = replay(raw).qpos
        scene = scene_for(raw)
        data = mujoco.MjData(scene.model)
        cameras = CameraRig(scene.model, profile)
        t0 = time.perf_counter()
        touch = TactileFrames(scene, profile)
        build_s = time.perf_counter() - t0
        camera_s, sense_s, write_s, contact, rays = [], [], [], [], []
        with EpisodeWriter(tmp / "tactile.h5", touch.static()) as writer:
            for step in frame_steps(len(qpos), profile.rate_hz):
                set_positions(scene.model, data, qpos[step])
                t0 = time.perf_counter()
                cameras.capture(data)
                t1 = time.perf_counter()
                frame = touch.rig.capture(data)
                t2 = time.perf_counter()
                writer.append(frame_datasets(frame))
                t3 = time.perf_counter()
                camera_s.append(t1 - t0)
                sense_s.append(t2 - t1)
                write_s.append(t3 - t2)
                contact.append(bool(frame.mask.any()))
                rays.append(frame.rays_cast)
            t_close = time.perf_counter()
        # the writer buffers small per-frame datasets (coarse tactile maps) and writes them on closing:
        # that deferred write is spread evenly over the frames
        deferred_s = (time.perf_counter() - t_close) / max(len(write_s), 1)
        write_s = [w + deferred_s for w in write_s]
        cameras.close()
        tactile_bytes = (tmp / "tactile.h5").stat().st_size
    tactile_s = np.add(sense_s, write_s)
    hit = np.array(contact)
    return {
        "profile": profile_name, "control_steps": steps, "frames": len(camera_s), "contact_frames": int(hit.sum()),
        "cameras": len(profile.camera_ids), "camera_resolution": [profile.width, profile.height],
        "tactile_sites": len(touch.rig.site_names), "tactile_shape": list(touch.rig.shape),
        "camera_ms_per_frame": _mean_ms(camera_s),
        "tactile_ms_per_frame": _mean_ms(list(tactile_s)),
        "tactile_sense_ms_per_frame": _mean_ms(sense_s), "tactile_write_ms_per_frame": _mean_ms(write_s),
        "tactile_ms_contact_frames": _mean_ms(list(tactile_s[hit])),
        "tactile_ms_no_contact_frames": _mean_ms(list(tactile_s[~hit])),
        "tactile_vs_camera_ratio": round(float(np.sum(tactile_s) / np.sum(camera_s)), 4),
        "rays_cast_per_frame": round(float(np.mean(rays)), 1),
        "rig_build_s": round(build_s, 3),
        "tactile_bytes_per_frame_on_disk": round(tactile_bytes / max(len(camera_s), 1)),
        "opencv_threads": cv2.getNumThreads(),
        "note": (f"scripted {TASK} on {EMBODIMENT}; --steps below {TACTILE_BENCH_MIN_STEPS} are raised to it so "
                 "the first grasp is in the window; camera = render of all cameras, tactile = sensing all sites + "
                 "HDF5 append; rig_build_s = surface maps + target BVHs, once per file"),
    }


def run(part: str, profile: str = "preview", steps: int = 120, workers: int = 1, setting: str | None = None) -> dict:
    if part == "recorder":
        return bench_recorder(steps)
    if part == "replay":
        return bench_replay(profile, steps, workers, setting)
    if part == "tactile-replay":
        return bench_tactile_replay(profile, steps)
    if part == "labels":     # ms per frame of each label against the RGB render of the same cameras
        from sim.labels.bench import run_bench
        return run_bench(profile, frames=max(1, steps // 3))
    raise ValueError(part)
