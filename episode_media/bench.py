"""`b2d bench media`: cost of `b2d export usd` and `b2d show` per frame, each beside a baseline from
the same run - posing the scene and building MuJoCo's visual scene (what any exporter must do) for
USD, reading the frame's images and tacmaps for `show`."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import mujoco

from episode_media.qpos import episode_qpos
from episode_media.source import episode_scene, frame_range
from episode_media.strip import EpisodeFrames, show_episode
from episode_media.usd_export import export_usd
from episodes import schema
from episodes.reader import open_episode
from sim.render import set_positions

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"


def _record_episode(tmp: Path, profile_name: str, steps: int) -> Path:
    from episodes.stages import raw_to_episode
    from sim.registry import sensor_profile
    from teleop.demos import record_demonstrations

    [rec] = record_demonstrations(TASK, EMBODIMENT, 1, tmp / "raw", max_steps=steps)
    if rec.error:
        raise RuntimeError(f"recording for the media benchmark failed: {rec.error}")
    return raw_to_episode(rec.path, sensor_profile(profile_name), tmp / "episodes")


def _posing_baseline_ms(episode: Path) -> float:
    with open_episode(episode) as reader:
        model = episode_scene(reader).model
        qpos = episode_qpos(reader, model)
    data, option, camera = mujoco.MjData(model), mujoco.MjvOption(), mujoco.MjvCamera()
    scene = mujoco.MjvScene(model, maxgeom=10000)
    t0 = time.perf_counter()
    for q in qpos:
        set_positions(model, data, q)
        mujoco.mjv_updateScene(model, data, option, None, camera, mujoco.mjtCatBit.mjCAT_ALL, scene)
    return 1e3 * (time.perf_counter() - t0) / len(qpos)


def _reading_baseline_ms(episode: Path) -> float:
    with open_episode(episode) as reader:
        images = EpisodeFrames(reader, frame_range(episode, reader.num_frames))
        t0 = time.perf_counter()
        for k in range(reader.num_frames):
            for cam in images.cameras:
                reader.read(f"cameras/{cam}/rgb", k, k + 1)
            for site in images.sites:
                reader.read(schema.tactile_path("tacmap", site), k, k + 1)
        return 1e3 * (time.perf_counter() - t0) / reader.num_frames


def run_media_bench(profile: str = "preview", steps: int = 120) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        episode = _record_episode(tmp, profile, steps)
        usd = export_usd(episode, tmp / "usd")
        usd_bytes = sum(p.stat().st_size for p in (tmp / "usd").rglob("*") if p.is_file())
        posing_ms = _posing_baseline_ms(episode)
        t0 = time.perf_counter()
        mp4 = show_episode(episode, tmp / "show.mp4")
        mp4_ms = 1e3 * (time.perf_counter() - t0) / mp4.frames
        t0 = time.perf_counter()
        png = show_episode(episode, tmp / "show.png")
        png_ms = 1e3 * (time.perf_counter() - t0) / png.frames
        reading_ms = _reading_baseline_ms(episode)
        with open_episode(episode) as reader:
            cameras, sites = len(reader.camera_ids), len(reader.tactile_sites)
        mp4_bytes, png_bytes = mp4.path.stat().st_size, png.path.stat().st_size
    return {
        "profile": profile, "frames": usd.frames, "cameras": cameras, "tactile_sites": sites,
        "export_usd": {"setup_s": usd.setup_s, "ms_per_frame": usd.ms_per_frame, "save_s": usd.save_s,
                       "baseline_pose_and_visual_scene_ms_per_frame": posing_ms,
                       "bytes_per_frame": usd_bytes / usd.frames,
                       "note": "setup is the exporter building each geom's mesh once (pure Python in mujoco.usd)"},
        "show": {"mp4_ms_per_frame": mp4_ms, "png_strip_ms_per_frame": png_ms, "mp4_written": mp4.kind == "mp4",
                 "baseline_read_frame_ms": reading_ms,
                 "mp4_bytes_per_frame": mp4_bytes / mp4.frames, "png_bytes_per_frame": png_bytes / png.frames},
    }
