"""The per-episode HDF5 layout (paper appendix "HDF5 Schema Details"): one module owns it.

Writers and the validator both read these declarations; a reader never needs to know how a file
was written. Shapes use symbols: T frames, J robot joints, A actions, H/W camera pixels,
S tactile sites, Ht/Wt tactile pixels. `None` in a shape means "any".
"""

from __future__ import annotations

from dataclasses import dataclass

from sim.registry import LABEL_MODALITIES  # noqa: F401  (re-exported)

# 2: robot/tactile/*, labels/ and cameras/*/semantic_seg, instance_seg, articulated-object joint states
# and distractors under objects/.
SCHEMA_VERSION = "b2d.episode/2"
MANIFEST_NAME = "episode_manifest.json"


@dataclass(frozen=True)
class Node:
    path: str                  # relative; "{camera_id}" / "{obj_id}" / "{site}" are placeholders
    kind: str                  # "dataset" | "group"
    dtype: str | None = None   # numpy kind: "uint8", "float32", "float64", "int64", "bool", "str"
    shape: tuple | None = None
    required: bool = True
    modality: str | None = None


META_FIELDS = ("task", "embodiment", "instruction", "scene", "modalities", "cameras",
               "collection_config", "success", "schema_version", "dataset", "replay_fidelity")

EPISODE_NODES = (
    *(Node(f"meta/{name}", "dataset", "str" if name != "success" else "bool", ()) for name in META_FIELDS),
    Node("time/frame_index", "dataset", "int64", ("T",)),
    Node("time/timestamp_ns", "dataset", "int64", ("T",)),
    Node("time/sim_step", "dataset", "int64", ("T",)),
    Node("episode/is_first", "dataset", "bool", ("T",)),
    Node("episode/is_last", "dataset", "bool", ("T",)),
    Node("episode/done", "dataset", "bool", ("T",)),
    Node("episode/success", "dataset", "bool", ("T",)),
    Node("action/action", "dataset", "float64", ("T", "A")),
    Node("action/valid", "dataset", "bool", ("T",)),
    Node("action/names", "dataset", "str", ("A",)),
    Node("action/source", "dataset", "str", ()),
    Node("action/control_mode", "dataset", "str", ()),
    Node("action/action_type", "dataset", "str", ()),
    # b2d additions: the operator stream's StepFlag bits (teleop/streams/sanitizer.py) OR-ed over the control
    # steps of each frame, and their reasons (one per line, "" = clean)
    Node("action/stream_flags", "dataset", "uint8", ("T",)),
    Node("action/stream_reasons", "dataset", "str", ("T",)),
    Node("frame_valid", "dataset", "bool", ("T",)),
    Node("frame_errors", "dataset", "str", ("T",)),
    Node("robot/joint_names", "dataset", "str", ("J",)),
    Node("robot/qpos", "dataset", "float64", ("T", "J"), modality="robot_state"),
    Node("robot/qvel", "dataset", "float64", ("T", "J"), modality="robot_state"),
    Node("robot/qeffort", "dataset", "float64", ("T", "J"), modality="robot_state"),
    Node("metrics/episode", "dataset", "str", ()),
    Node("metrics/timeseries", "group"),
)

CAMERA_NODES = (
    Node("rgb", "dataset", "uint8", ("T", "H", "W", 3), modality="rgb"),
    Node("depth_m", "dataset", "float32", ("T", "H", "W"), modality="depth"),
    Node("depth_semantics", "dataset", "str", (), modality="depth"),
    Node("intrinsic", "dataset", "float64", (3, 3)),
    Node("extrinsic_world_from_cam", "dataset", "float64", ("T", 4, 4)),
    Node("camera_model", "dataset", "str", ()),
    Node("clip_range_m", "dataset", "float64", (2,)),
)

OBJECT_NODES = (
    Node("pose_world", "dataset", "float64", ("T", 7), modality="object_state"),
    Node("lin_vel_world", "dataset", "float64", ("T", 3), modality="object_state"),
    Node("ang_vel_world", "dataset", "float64", ("T", 3), modality="object_state"),
)
# Articulated objects (doors, lids, keys): required when objects/{obj_id}/joint_names is present. K joints,
# named "<object>/<link>"; qeffort is the passive + constraint generalized force (springs, limits, contacts).
OBJECT_JOINT_NODES = (
    Node("joint_names", "dataset", "str", ("K",), modality="object_state"),
    Node("qpos", "dataset", "float64", ("T", "K"), modality="object_state"),
    Node("qvel", "dataset", "float64", ("T", "K"), modality="object_state"),
    Node("qeffort", "dataset", "float64", ("T", "K"), modality="object_state"),
)

# Tactile (paper: robot/tactile/meta, tacmap/{site}, distance_along_normal_m/{site}, contact_mask/{site}),
# required when meta/modalities lists "tactile" or the collection profile enables it. S sites;
# surface/{site} holds each site's point (mm) and inward-normal maps on the stored grid.
TACTILE_ROOT = "robot/tactile"
TACTILE_NODES = (
    Node("robot/tactile/meta", "dataset", "str", (), modality="tactile"),
    Node("robot/tactile/site_names", "dataset", "str", ("S",), modality="tactile"),
)
TACTILE_SITE_NODES = (
    Node("robot/tactile/tacmap/{site}", "dataset", "uint8", ("T", "Ht", "Wt"), modality="tactile"),
    Node("robot/tactile/distance_along_normal_m/{site}", "dataset", "float32", ("T", "Ht", "Wt"), modality="tactile"),
    Node("robot/tactile/contact_mask/{site}", "dataset", "bool", ("T", "Ht", "Wt"), modality="tactile"),
    Node("robot/tactile/surface/{site}/point_mm", "dataset", "float32", ("Ht", "Wt", 3), modality="tactile"),
    Node("robot/tactile/surface/{site}/normal", "dataset", "float32", ("Ht", "Wt", 3), modality="tactile"),
)
TACTILE_PER_FRAME = ("tacmap", "distance_along_normal_m", "contact_mask")


def tactile_path(kind: str, site: str) -> str:
    """Per-site tactile dataset, e.g. tactile_path("tacmap", "right_index_tip")."""
    return f"{TACTILE_ROOT}/{kind}/{site}"


# Labels (sim/labels), each required when meta/modalities lists its modality or the collection
# profile's modalities do. Paper: labels/box2d/{camera_id}/{obj_id}/ (xyxy [T,4], visibility [T]),
# labels/box3d/{obj_id}/ (center_world, size_lwh, quat_world) and labels/occupancy_tsdf/ (grid,
# grid shape, bounds, voxel size, method, semantics, frame-valid flags). b2d additions to the paper's
# table: semantic and instance segmentation per camera (cameras/{camera_id}/semantic_seg, instance_seg),
# the id maps stored once as JSON (labels/semantic_classes {id: class}, labels/instances
# {id: {name, category, semantic_id}}; instance ids follow objects/: task objects, then distractors)
# and the per-voxel instance ids (labels/occupancy_tsdf/instance_grid). X, Y, Z: voxels per axis.
# LABEL_MODALITIES: the profile parser's list (sim.registry), imported so the two cannot drift apart.
LABEL_ID_NODES = (
    Node("labels/semantic_classes", "dataset", "str", ()),
    Node("labels/instances", "dataset", "str", ()),
)
BOX2D_SEMANTICS_NODE = Node("labels/box2d_semantics", "dataset", "str", (), modality="box2d")  # conventions (JSON)
SEGMENTATION_CAMERA_NODES = (
    Node("semantic_seg", "dataset", "uint8", ("T", "H", "W"), modality="segmentation"),
    Node("instance_seg", "dataset", "uint16", ("T", "H", "W"), modality="segmentation"),
)
BOX2D_NODES = (     # under labels/box2d/{camera_id}/{obj_id}/
    Node("xyxy", "dataset", "float32", ("T", 4), modality="box2d"),
    Node("visibility", "dataset", "float32", ("T",), modality="box2d"),
)
BOX3D_NODES = (     # under labels/box3d/{obj_id}/
    Node("center_world", "dataset", "float64", ("T", 3), modality="box3d"),
    Node("size_lwh", "dataset", "float64", ("T", 3), modality="box3d"),
    Node("quat_world", "dataset", "float64", ("T", 4), modality="box3d"),
)
OCCUPANCY_ROOT = "labels/occupancy_tsdf"
OCCUPANCY_NODES = (
    Node(f"{OCCUPANCY_ROOT}/grid", "dataset", "uint8", ("T", "X", "Y", "Z"), modality="occupancy"),
    Node(f"{OCCUPANCY_ROOT}/instance_grid", "dataset", "uint16", ("T", "X", "Y", "Z"), modality="occupancy"),
    Node(f"{OCCUPANCY_ROOT}/grid_shape", "dataset", "int64", (3,), modality="occupancy"),
    Node(f"{OCCUPANCY_ROOT}/bounds_m", "dataset", "float64", (2, 3), modality="occupancy"),
    Node(f"{OCCUPANCY_ROOT}/voxel_size_m", "dataset", "float64", (), modality="occupancy"),
    Node(f"{OCCUPANCY_ROOT}/method", "dataset", "str", (), modality="occupancy"),
    Node(f"{OCCUPANCY_ROOT}/semantics", "dataset", "str", (), modality="occupancy"),
    Node(f"{OCCUPANCY_ROOT}/frame_valid", "dataset", "bool", ("T",), modality="occupancy"),
)
BOX2D_XYXY = ("pixel-edge image coordinates [x1, y1, x2, y2] of the object's visible pixels (pixel (u, v) "
              "covers [u, u+1) x [v, v+1): x1, y1 inclusive, x2, y2 exclusive), modal and clipped to the "
              "image; NaN with visibility 0 when no pixel shows the object")
BOX2D_VISIBILITY = ("fraction of the object's area-uniform surface samples that project into the image onto "
                    "a pixel (or a 4-neighbour) showing the object in the instance mask")


def box2d_path(camera: str, obj: str, kind: str) -> str:
    return f"labels/box2d/{camera}/{obj}/{kind}"


def box3d_path(obj: str, kind: str) -> str:
    return f"labels/box3d/{obj}/{kind}"


DEPTH_SEMANTICS = ("metric z-depth in metres along the camera optical axis (OpenCV camera frame: "
                   "x right, y down, z forward); the far clip value where nothing is hit")
CAMERA_MODEL = "pinhole"
CONTROL_MODE = "absolute_joint_position"
ACTION_TYPE = "joint_position_target"

# Per-dataset storage (episodes/writer.py): one frame per chunk for images; Zstd or Blosc LZ4 throughout.
IMAGE_CHUNK_FRAMES = 1


def episode_filename(episode_id: str) -> str:
    return f"episode_{episode_id}.hdf5"
