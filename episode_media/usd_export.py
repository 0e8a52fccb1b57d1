"""`b2d export usd`: an episode's motion as an animated USD stage, written by MuJoCo's exporter.

The scene is rebuilt from the episode's meta, posed from the full qpos of each chosen frame
(kinematics only, no physics) and handed to `mujoco.usd.exporter.USDExporter`, one time code per
frame. Output is the exporter's package layout, written to a temporary folder and renamed:

    OUT/frames/<episode>.usdc    the stage (textures referenced as ../assets/...)
    OUT/assets/texture_*.png
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import mujoco

from episode_media.qpos import episode_qpos
from episode_media.source import episode_scene, frame_range, frame_rate_hz
from episodes.atomic import atomic_dir
from episodes.reader import open_episode
from sim.errors import SpecError
from sim.render import set_positions

FORMATS = ("usdc", "usda")


@dataclass(frozen=True)
class UsdExport:
    path: Path               # the stage file
    frames: int
    fps: float
    setup_s: float           # exporter start and first frame: every geom's mesh is built once
    ms_per_frame: float      # each later frame: kinematics + exporter update
    save_s: float


def default_out(episode: Path) -> Path:
    return Path(f"{episode.stem}_usd")


def is_usd_package(path: Path) -> bool:
    """An earlier output of this command (safe to replace)."""
    if not path.is_dir() or not (path / "frames").is_dir():
        return False
    return {p.name for p in path.iterdir()} <= {"frames", "assets"} and any(
        p.suffix in (".usd", ".usdc", ".usda") for p in (path / "frames").iterdir())


def export_usd(episode: str | Path, out: str | Path | None = None, frames: str | None = None, stride: int = 1,
               file_format: str = "usdc") -> UsdExport:
    episode = Path(episode)
    out = Path(out) if out is not None else default_out(episode)
    if file_format not in FORMATS:
        raise SpecError(episode, "--format", f"one of {', '.join(FORMATS)}", file_format)
    if out.exists() and not is_usd_package(out):
        raise SpecError(out, "--out", "a new folder or an earlier `b2d export usd` output (refusing to replace "
                                      "another folder)")
    with open_episode(episode) as reader:
        chosen = frame_range(episode, reader.num_frames, frames, stride)
        model = episode_scene(reader).model
        qpos = episode_qpos(reader, model, chosen)
        fps = frame_rate_hz(reader, chosen)
        cameras = [c for c in reader.camera_ids if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, c) >= 0]
        layer_data = {"b2d_episode": episode.name, "b2d_task": str(reader.meta("task")),
                      "b2d_embodiment": str(reader.meta("embodiment")), "b2d_first_frame": int(chosen.start),
                      "b2d_frame_stride": int(chosen.stride)}
    return _write(model, qpos, fps, cameras, layer_data, out, f"{episode.stem}.{file_format}", file_format)


def _write(model, qpos, fps, cameras, layer_data, out: Path, stage_name: str, file_format: str) -> UsdExport:
    from mujoco.usd.exporter import USDExporter   # needs usd-core and pillow

    data = mujoco.MjData(model)
    with atomic_dir(out, is_usd_package) as tmp:
        t0 = time.perf_counter()
        exporter = USDExporter(model, output_directory=tmp.name, output_directory_root=str(tmp.parent),
                               camera_names=cameras, verbose=False)
        t_first = None
        for q in qpos:
            set_positions(model, data, q)
            exporter.update_scene(data)
            t_first = t_first or time.perf_counter()
        t1 = time.perf_counter()
        stage = exporter.stage
        stage.SetTimeCodesPerSecond(fps)
        stage.GetRootLayer().customLayerData = layer_data
        exporter.save_scene(filetype=file_format)
        # save_scene names the file frame_<N> and ends the stage at time code N, one past the last
        # sample (where it hides every geom); end it at the last frame and give it the episode's name
        exporter_file = tmp / "frames" / f"frame_{exporter.frame_count}.{file_format}"
        stage.SetEndTimeCode(len(qpos) - 1)
        stage.Export(str(tmp / "frames" / stage_name))
        exporter_file.unlink()
        t2 = time.perf_counter()
    later = len(qpos) - 1
    return UsdExport(path=out / "frames" / stage_name, frames=len(qpos), fps=fps, setup_s=t_first - t0,
                     ms_per_frame=1e3 * (t1 - t_first) / later if later else float("nan"), save_s=t2 - t1)
