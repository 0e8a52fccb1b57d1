"""Scene samples: the resolved generalization configuration g_e of one episode.

`S_e = Build(T, g_e)`: a SceneSample holds every resolved factor (background, tabletop texture,
lighting, distractors, camera pose offsets, object poses, table height) and is stored as JSON with
the episode, so any channel is replayable and auditable. Sampling follows the paper's appendix
"Generalization Configuration" and its channel table.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from sim.registry import Channel, names
from sim.scene import assets
from sim.tasks import TaskSpec

SEED_NAMESPACE = 100_000_000        # per-task seed namespace (reference implementation)
FULL_CHANNEL_SEED_BASE = 7_000_000_000   # inv_equi draws from its own base: it has no anchor
POSE_XY_RANGE_M = 0.02
POSE_YAW_RANGE_DEG = 10.0
TABLE_HEIGHT_RANGE_M = 0.05
POSE_SHRINK = (1.0, 0.5, 0.25)      # progressive reduction when a perturbed pose collides
PLACEMENT_CLEARANCE_M = 0.01
CAMERA_WORLD_MM, CAMERA_DIST_M, CAMERA_DEG = 5.0, 0.03, 1.0
WORLD_CAMERAS = ("chest", "overhead", "stereo_left", "stereo_right")
WRIST_CAMERAS = ("left_wrist", "right_wrist")
DISTRACTOR_EDGE_MARGIN_M = 0.05
CENTRAL_EXCLUSION = ((-0.25, 0.25), (-0.20, 0.35))   # x range, y range (paper)


@dataclass(frozen=True)
class SceneSample:
    task: str
    channel: str
    seed: int
    anchor: str | None
    table_height: float
    object_poses: dict[str, list[float]]          # name -> [x, y, yaw_deg]
    background: dict
    table_texture: dict
    lighting: dict
    distractors: list[dict] = field(default_factory=list)
    camera_offsets: dict[str, dict] = field(default_factory=dict)   # cam -> {pos, rpy_deg}

    def to_json(self) -> str:
        return json.dumps(asdict(self), sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> "SceneSample":
        return cls(**json.loads(text))


def task_seed(task_index: int, episode_index: int) -> int:
    return task_index * SEED_NAMESPACE + episode_index


def demonstration_seed(task: str, index: int) -> int:
    """The seed of a task's demonstration `index` (`b2d record`'s episode `index`)."""
    return task_seed(names("tasks").index(task), index)


# ---------------------------------------------------------------- equivariance factors


def _overlaps(xy, radius, placed) -> bool:
    return any(np.hypot(xy[0] - p[0], xy[1] - p[1]) < radius + r + PLACEMENT_CLEARANCE_M
               for p, r in placed)


def zone_point(zone: dict, rng: np.random.Generator) -> np.ndarray:
    """A uniform draw from a zone: a rectangle {xy_min, xy_max} or a disc {center_xy, radius}
    (uniform over the disc's area, hence the square root on the radius)."""
    if "radius" in zone:
        r = zone["radius"] * np.sqrt(rng.uniform())
        angle = rng.uniform(0.0, 2 * np.pi)
        return np.asarray(zone["center_xy"], float) + r * np.array([np.cos(angle), np.sin(angle)])
    return rng.uniform(np.asarray(zone["xy_min"], float), np.asarray(zone["xy_max"], float))


def sample_object_poses(task: TaskSpec, rng: np.random.Generator) -> dict[str, list[float]]:
    """Explicit poses get +-2 cm / +-10 deg, shrunk on collision, and keep the nominal pose when
    no shrink fits; zoned objects are drawn in their zone (the 100th draw is kept even if it
    collides). An object `on` another keeps its offset in that object's frame (it moves with it)."""
    placed: list[tuple[tuple[float, float], float]] = []
    poses: dict[str, list[float]] = {}
    for name, obj in task.objects.items():
        radius = obj.footprint_radius
        if obj.on is not None:
            poses[name] = [round(v, 6) for v in _on_pose(poses[obj.on], obj)]
            continue
        if obj.zone is not None:
            for _ in range(100):
                xy = zone_point(task.zones[obj.zone], rng)
                if not _overlaps(xy, radius, placed):
                    break
            pose = [float(xy[0]), float(xy[1]), float(rng.uniform(-180, 180))]
        else:
            nominal = [obj.xy[0], obj.xy[1], obj.yaw_deg]
            pose = nominal
            if not obj.fixed_pose:
                dxy = rng.uniform(-POSE_XY_RANGE_M, POSE_XY_RANGE_M, 2)
                dyaw = rng.uniform(-POSE_YAW_RANGE_DEG, POSE_YAW_RANGE_DEG)
                for shrink in POSE_SHRINK:
                    xy = np.array(obj.xy) + shrink * dxy
                    if not _overlaps(xy, radius, placed):
                        pose = [float(xy[0]), float(xy[1]), float(obj.yaw_deg + shrink * dyaw)]
                        break
        placed.append(((pose[0], pose[1]), radius))
        poses[name] = [round(v, 6) for v in pose]
    return poses


def _on_pose(support: list[float], obj) -> list[float]:
    yaw = np.deg2rad(support[2])
    dx, dy = obj.xy
    return [support[0] + np.cos(yaw) * dx - np.sin(yaw) * dy, support[1] + np.sin(yaw) * dx + np.cos(yaw) * dy,
            support[2] + obj.yaw_deg]


def zone_centre(zone: dict) -> np.ndarray:
    if "radius" in zone:
        return np.asarray(zone["center_xy"], float)
    return (np.asarray(zone["xy_min"], float) + np.asarray(zone["xy_max"], float)) / 2


def nominal_object_poses(task: TaskSpec) -> dict[str, list[float]]:
    """The layout as written: declared poses, zoned objects at their zone's centre (yaw 0)."""
    poses: dict[str, list[float]] = {}
    for name, obj in task.objects.items():
        if obj.on is not None:
            poses[name] = _on_pose(poses[obj.on], obj)
        elif obj.zone is not None:
            poses[name] = [*zone_centre(task.zones[obj.zone]).tolist(), 0.0]
        else:
            poses[name] = [obj.xy[0], obj.xy[1], obj.yaw_deg]
    return {name: [round(float(v), 6) for v in pose] for name, pose in poses.items()}


def nominal_sample(task: TaskSpec) -> SceneSample:
    """The task's scene as written: nominal poses, table height and visuals, no distractors."""
    return SceneSample(
        task=task.name, channel="nominal", seed=0, anchor=None, table_height=task.table.height,
        object_poses=nominal_object_poses(task),
        background=dict(assets.NOMINAL_BACKGROUND), table_texture=dict(assets.NOMINAL_TEXTURE),
        lighting=json.loads(json.dumps(assets.NOMINAL_LIGHTING)),
    )


def sample_table_height(task: TaskSpec, rng: np.random.Generator) -> float:
    return round(task.table.height + float(rng.uniform(-TABLE_HEIGHT_RANGE_M, TABLE_HEIGHT_RANGE_M)), 6)


# ---------------------------------------------------------------- invariance factors


def sample_lighting(rng: np.random.Generator) -> dict:
    dome_color = np.array([0.8, 0.8, 0.6]) + rng.uniform(0, 1, 3) * np.array([0.2, 0.2, 0.4])
    return {
        "distant": {"intensity": float(rng.uniform(1000, 1500)),
                    "color": rng.uniform(0.4, 1.0, 3).round(4).tolist(),
                    "pitch_deg": float(rng.uniform(-30, -5)), "yaw_deg": float(rng.uniform(-90, 90)),
                    "angular_size_deg": float(rng.uniform(0.5, 1.0))},
        "dome": {"intensity": float(rng.uniform(150, 350)), "color": dome_color.round(4).tolist(),
                 "exposure": float(rng.uniform(-0.5, 0.5))},
    }


def sample_camera_offsets(rng: np.random.Generator) -> dict[str, dict]:
    def world():
        return {"pos": (rng.uniform(-1, 1, 3) * CAMERA_WORLD_MM / 1000).round(6).tolist(),
                "target": (rng.uniform(-1, 1, 3) * CAMERA_WORLD_MM / 1000).round(6).tolist(),
                "distance": round(float(rng.uniform(-CAMERA_DIST_M, CAMERA_DIST_M)), 6),
                "rpy_deg": rng.uniform(-CAMERA_DEG, CAMERA_DEG, 3).round(4).tolist()}

    offsets = {cam: world() for cam in ("chest", "overhead")}
    stereo = world()   # the stereo pair shares one sample to keep its relative pose
    offsets["stereo_left"] = offsets["stereo_right"] = stereo
    for cam in WRIST_CAMERAS:
        offsets[cam] = {"pos": (rng.uniform(-1, 1, 3) * CAMERA_WORLD_MM / 1000).round(6).tolist(),
                        "target": [0.0, 0.0, 0.0], "distance": 0.0,
                        "rpy_deg": rng.uniform(-CAMERA_DEG, CAMERA_DEG, 3).round(4).tolist()}
    return offsets


def sample_distractors(task: TaskSpec, object_poses, rng: np.random.Generator, split: str) -> list[dict]:
    ids = assets.DISTRACTORS.ids(split)
    half_x, half_y = task.table.size_xy[0] / 2, task.table.size_xy[1] / 2
    placed = [((p[0], p[1]), task.objects[n].footprint_radius) for n, p in object_poses.items()]
    chosen = []
    for _ in range(int(rng.integers(1, 4))):
        params = assets.distractor_params(ids[int(rng.integers(len(ids)))])
        scale = float(rng.uniform(0.8, 1.2))
        radius = float(np.hypot(*(np.array(params["size"][:2] + params["size"][:1])[:2]))) * scale
        for _ in range(200):
            xy = rng.uniform([-half_x + DISTRACTOR_EDGE_MARGIN_M, -half_y + DISTRACTOR_EDGE_MARGIN_M],
                             [half_x - DISTRACTOR_EDGE_MARGIN_M, half_y - DISTRACTOR_EDGE_MARGIN_M])
            (x0, x1), (y0, y1) = CENTRAL_EXCLUSION
            if x0 <= xy[0] <= x1 and y0 <= xy[1] <= y1:
                continue
            if not _overlaps(xy, radius, placed):
                placed.append(((xy[0], xy[1]), radius))
                chosen.append({**params, "split": split, "scale": round(scale, 4),
                               "xy": xy.round(6).tolist(), "yaw_deg": round(float(rng.uniform(-180, 180)), 4)})
                break
    return chosen


def _invariance(task: TaskSpec, object_poses, rng: np.random.Generator, split: str) -> dict:
    bg = assets.BACKGROUNDS.ids(split)
    tex = assets.TEXTURES.ids(split)
    return {
        "background": {**assets.background_params(bg[int(rng.integers(len(bg)))]), "split": split},
        "table_texture": {**assets.texture_params(tex[int(rng.integers(len(tex)))]), "split": split},
        "lighting": sample_lighting(rng),
        "distractors": sample_distractors(task, object_poses, rng, split),
        "camera_offsets": sample_camera_offsets(rng),
    }


# ---------------------------------------------------------------- samples per use


def demonstration_sample(task: TaskSpec, seed: int) -> SceneSample:
    """A demonstration scene: nominal visuals, object poses and table height varied so that the
    demonstrations (the evaluation anchors) cover the equivariance range."""
    rng = np.random.default_rng(seed)
    return SceneSample(
        task=task.name, channel="demo", seed=seed, anchor=None,
        table_height=sample_table_height(task, rng),
        object_poses=sample_object_poses(task, rng),
        background=dict(assets.NOMINAL_BACKGROUND), table_texture=dict(assets.NOMINAL_TEXTURE),
        lighting=json.loads(json.dumps(assets.NOMINAL_LIGHTING)),
    )


def channel_sample(task: TaskSpec, channel: Channel, seed: int, anchor: SceneSample | None,
                   anchor_id: str | None = None) -> SceneSample:
    """Resolve the scene of one evaluation episode under a generalization channel."""
    if channel.anchored:
        if anchor is None:
            raise ValueError(f"channel '{channel.name}' needs an anchor episode")
        base = replace(anchor, channel=channel.name, seed=seed, anchor=anchor_id)
    else:
        base = demonstration_sample(task, FULL_CHANNEL_SEED_BASE + seed)
        base = replace(base, channel=channel.name, seed=seed, anchor=None)
    rng = np.random.default_rng(seed)
    if channel.resample_equivariance:
        base = replace(base, table_height=sample_table_height(task, rng),
                       object_poses=sample_object_poses(task, rng))
    if channel.resample_invariance:
        base = replace(base, **_invariance(task, base.object_poses, rng, split="unseen"))
    return base
