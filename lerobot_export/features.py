"""LeRobot features for a b2d layout, and one episode's frame table.

Keys follow lerobot's conventions: `observation.state` (joint positions, named), `observation.velocity`,
`observation.effort`, `action` (joint position targets, named), `observation.images.<view>` (MP4
videos), `next.done` / `next.success`, and the default index columns. b2d additions: each tactile site
as a one-channel image feature `observation.tactile.<site>` (the stored TacMap, lossless PNG, with its
encoding in the feature's info) and GR00T's task annotation column. Vectors are float32, the dtype
GR00T and openpi read; the HDF5 keeps float64."""

from __future__ import annotations

import io
import json

import numpy as np
import pyarrow as pa
from PIL import Image

from episodes import schema
from episodes.reader import EpisodeReader
from lerobot_export.source import Layout
from lerobot_export.stats import ImageStats, vector_stats

STATE, VELOCITY, EFFORT, ACTION = "observation.state", "observation.velocity", "observation.effort", "action"
TASK_ANNOTATION = "annotation.human.action.task_description"   # GR00T reads the task from this column
VECTORS = ((STATE, "robot/qpos"), (VELOCITY, "robot/qvel"), (EFFORT, "robot/qeffort"), (ACTION, "action/action"))
FLAGS = (("next.done", "episode/done"), ("next.success", "episode/success"))
INDEX_COLUMNS = ("timestamp", "frame_index", "episode_index", "index", "task_index")
IMAGE_NAMES = ["height", "width", "channels"]
FRAME_CHUNK = 64      # camera frames read, encoded and counted at a time


def view_key(camera: str) -> str:
    return f"observation.images.{camera}"


def tactile_key(site: str) -> str:
    return f"observation.tactile.{site}"


def _scalar(dtype: str) -> dict:
    return {"dtype": dtype, "shape": [1], "names": None}


def info_features(layout: Layout, video_infos: dict[str, dict]) -> dict:
    """The `features` block of meta/info.json."""
    features = {}
    for key, _ in VECTORS:
        names = layout.action_names if key == ACTION else layout.state_names
        features[key] = {"dtype": "float32", "shape": [len(names)], "names": list(names)}
    for key, _ in FLAGS:
        features[key] = _scalar("bool")
    features[TASK_ANNOTATION] = _scalar("int64")
    for cam, h, w in layout.views:
        features[view_key(cam)] = {"dtype": "video", "shape": [h, w, 3], "names": IMAGE_NAMES,
                                   "info": video_infos.get(view_key(cam), {})}
    encoding = json.loads(layout.tactile_encoding) if layout.tactile_encoding else {}
    for site, h, w in layout.tactile:
        features[tactile_key(site)] = {
            "dtype": "image", "shape": [h, w, 1], "names": IMAGE_NAMES,
            "info": {"tactile.site": site, "tactile.source": schema.tactile_path("tacmap", site),
                     "tactile.encoding": encoding}}
    features["timestamp"] = _scalar("float32")
    for key in INDEX_COLUMNS[1:]:
        features[key] = _scalar("int64")
    return features


def _arrow_type(feature: dict) -> pa.DataType:
    if feature["dtype"] == "image":
        return pa.struct([("bytes", pa.binary()), ("path", pa.string())])
    scalar = {"float32": pa.float32(), "int64": pa.int64(), "bool": pa.bool_()}[feature["dtype"]]
    return scalar if feature["shape"] == [1] else pa.list_(scalar, feature["shape"][0])


def _hf_type(feature: dict) -> dict:
    if feature["dtype"] == "image":
        return {"_type": "Image"}
    value = {"dtype": feature["dtype"], "_type": "Value"}
    return value if feature["shape"] == [1] else {"feature": value, "length": feature["shape"][0], "_type": "Sequence"}


def data_schema(features: dict) -> pa.Schema:
    """The parquet schema of the frame tables, with the Hugging Face `datasets` feature types in its
    metadata (so `datasets` decodes the tactile columns as images, as lerobot's loader expects)."""
    columns = {k: f for k, f in features.items() if f["dtype"] != "video"}
    hf = {"info": {"features": {k: _hf_type(f) for k, f in columns.items()}}}
    return pa.schema([pa.field(k, _arrow_type(f)) for k, f in columns.items()],
                     metadata={"huggingface": json.dumps(hf)})


def _png(image: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(image)).save(buffer, format="PNG")   # uint8 [H, W]: mode "L"
    return buffer.getvalue()


def frame_table(reader: EpisodeReader, layout: Layout, schema_: pa.Schema, episode_index: int,
                task_index: int, first_index: int) -> tuple[pa.Table, dict]:
    """One episode's rows (all but the videos) and the stats of its non-video features."""
    frames = reader.num_frames
    columns, stats = {}, {}
    for key, path in VECTORS:
        values = reader.read(path).astype(np.float32)
        columns[key] = pa.FixedSizeListArray.from_arrays(pa.array(values.reshape(-1)), values.shape[1])
        stats[key] = vector_stats(values)
    for key, path in FLAGS:
        values = reader.read(path).astype(bool)
        columns[key], stats[key] = pa.array(values), vector_stats(values)
    for site, _, _ in layout.tactile:
        maps = reader.read(schema.tactile_path("tacmap", site))
        columns[tactile_key(site)] = pa.array([{"bytes": _png(m), "path": None} for m in maps],
                                              type=_arrow_type({"dtype": "image"}))
        image_stats = ImageStats()
        image_stats.add(maps)
        stats[tactile_key(site)] = image_stats.result()
    frame_index = np.arange(frames, dtype=np.int64)
    indices = {"timestamp": (frame_index / layout.fps).astype(np.float32), "frame_index": frame_index,
               "episode_index": np.full(frames, episode_index, np.int64),
               "index": first_index + frame_index, "task_index": np.full(frames, task_index, np.int64)}
    columns[TASK_ANNOTATION] = pa.array(indices["task_index"])
    stats[TASK_ANNOTATION] = vector_stats(indices["task_index"])
    for key, values in indices.items():
        columns[key], stats[key] = pa.array(values), vector_stats(values)
    table = pa.table([columns[f.name] for f in schema_], schema=schema_)
    return table, stats
