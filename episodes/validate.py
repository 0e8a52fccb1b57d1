"""Check an HDF5 episode: the schema (every missing or malformed node), a full decode and the manifest's
checksums (episodes/integrity.py)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import h5py
import hdf5plugin  # noqa: F401  (registers the image filters: a file is checked by reading it)
import numpy as np

from episodes import integrity, schema
from episodes.atomic import file_sha256
from sim.errors import SpecError

_KIND = {"uint8": "u", "uint16": "u", "float32": "f", "float64": "f", "int64": "i", "bool": "b", "str": "O"}


def _check_node(f: h5py.File, base: str, node: schema.Node, dims: dict, problems: list[str]) -> None:
    path = f"{base}{node.path}"
    if path not in f:
        if node.required:
            problems.append(f"{path}: missing ({node.kind})")
        return
    obj = f[path]
    if node.kind == "group":
        if not isinstance(obj, h5py.Group):
            problems.append(f"{path}: expected a group")
        return
    if not isinstance(obj, h5py.Dataset):
        problems.append(f"{path}: expected a dataset")
        return
    kind = obj.dtype.kind if obj.dtype.kind != "S" else "O"
    if node.dtype and kind != _KIND[node.dtype] or (node.dtype in ("uint8", "uint16", "float32") and obj.dtype != np.dtype(node.dtype)):
        problems.append(f"{path}: dtype {obj.dtype}, expected {node.dtype}")
    if node.shape is None:
        return
    if len(obj.shape) != len(node.shape):
        problems.append(f"{path}: shape {obj.shape}, expected {node.shape}")
        return
    for axis, (got, want) in enumerate(zip(obj.shape, node.shape)):
        if isinstance(want, int):
            if got != want:
                problems.append(f"{path}: axis {axis} is {got}, expected {want}")
        elif want in dims:
            if got != dims[want]:
                problems.append(f"{path}: axis {axis} ({want}) is {got}, expected {dims[want]}")
        else:
            dims[want] = got


def validate_episode(path: str | Path, decode: bool = True, manifest: bool = True) -> list[str]:
    """Return the list of problems (empty when the episode is intact and matches the schema): the
    schema, then (`decode`) every dataset read whole, then (`manifest`) the file's sha256 and its
    datasets' digests against the `episode_manifest.json` beside it, when there is one."""
    path = Path(path)
    if not path.is_file():
        return ["<file>: no such file"]
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        return [f"<file>: not a readable HDF5 file ({integrity.short_error(exc)})"]
    problems: list[str] = []
    with f:
        for check, wanted in ((_check_schema, True), (_check_decode, decode), (_check_manifest, manifest)):
            if not wanted:
                continue
            try:
                check(path, f, problems)
            except Exception as exc:      # corrupt metadata can fail anywhere: one line, not a traceback
                problems.append(f"<file>: cannot be read ({integrity.short_error(exc)}): the file is corrupt")
    return problems


def _check_decode(path: Path, f: h5py.File, problems: list[str]) -> None:
    problems += integrity.decode_problems(f)


def _check_manifest(path: Path, f: h5py.File, problems: list[str]) -> None:
    from episodes.manifest import read_manifest     # the manifest module reads episodes with the reader

    source = schema.MANIFEST_NAME
    try:
        entries = read_manifest(path.parent)
    except SpecError as exc:
        problems.append(f"{source}: {exc}")
        return
    if not entries:
        return
    entry = entries.get(path.name)
    if entry is None:
        problems.append(f"<file>: not listed in {path.parent / source} (not written there by b2d)")
        return
    if entry.get("bytes") == path.stat().st_size and entry.get("sha256") == file_sha256(path):
        return
    problems.append(f"<file>: sha256 or size differs from {source} (the file changed after it was written)")
    if isinstance(entry.get("datasets"), dict):
        changed = integrity.compare_digests(entry["datasets"], integrity.dataset_digests(f), source)
        problems += changed or ["<file>: the datasets' data is as written: HDF5 structure bytes changed"]


def _check_schema(path: Path, f: h5py.File, problems: list[str]) -> None:
    version = f.attrs.get("schema_version")
    if version != schema.SCHEMA_VERSION:
        problems.append(f"/: schema_version {version!r}, expected {schema.SCHEMA_VERSION!r}")
    dims: dict = {}
    for node in schema.EPISODE_NODES:
        _check_node(f, "", node, dims, problems)
    modalities = _modalities(f, problems)
    cameras = list(f["cameras"].keys()) if "cameras" in f else []
    if ("rgb" in modalities or "depth" in modalities) and not cameras:
        problems.append("cameras/: missing although meta/modalities lists camera modalities")
    for cam in cameras:
        cam_dims = dict(dims)
        for node in schema.CAMERA_NODES:
            if node.modality in ("rgb", "depth") and node.modality not in modalities:
                continue
            _check_node(f, f"cameras/{cam}/", node, cam_dims, problems)
    _check_tactile(f, dims, modalities, problems)
    _check_labels(f, dims, modalities, cameras, problems)
    for obj in _scene_objects(f):       # a deleted object group read "ok" before (issue 23)
        if f"objects/{obj}" not in f:
            problems.append(f"objects/{obj}: missing (meta/scene places the object '{obj}')")
    for obj in (list(f["objects"].keys()) if "objects" in f else []):
        obj_dims = dict(dims)
        for node in schema.OBJECT_NODES:
            _check_node(f, f"objects/{obj}/", node, obj_dims, problems)
        articulated = any(f"objects/{obj}/{n.path}" in f for n in schema.OBJECT_JOINT_NODES)
        for node in schema.OBJECT_JOINT_NODES if articulated else ():
            _check_node(f, f"objects/{obj}/", node, obj_dims, problems)
    if "metrics/episode" in f:
        try:
            json.loads(f["metrics/episode"][()])
        except (ValueError, TypeError):
            problems.append("metrics/episode: expected a JSON document")
    for name, ds in (f["metrics/timeseries"].items() if "metrics/timeseries" in f else []):
        if not isinstance(ds, h5py.Dataset):
            problems.append(f"metrics/timeseries/{name}: expected a dataset")


def _scene_objects(f: h5py.File) -> list[str]:
    """The task objects meta/scene places ([] when it is absent or malformed: reported elsewhere)."""
    try:
        poses = json.loads(f["meta/scene"][()]).get("object_poses")
    except (KeyError, ValueError, TypeError, AttributeError):
        return []
    return sorted(poses) if isinstance(poses, dict) else []


def _modalities(f: h5py.File, problems: list[str]) -> list[str]:
    if "meta/modalities" not in f:
        return []
    try:
        return json.loads(f["meta/modalities"][()])
    except (ValueError, TypeError):
        problems.append("meta/modalities: expected a JSON list")
        return []


def _check_tactile(f: h5py.File, dims: dict, modalities: list[str], problems: list[str]) -> None:
    """robot/tactile/: required when listed in meta/modalities or enabled by the collection profile."""
    root = schema.TACTILE_ROOT
    listed, enabled = "tactile" in modalities, _profile_enables_tactile(f)
    if root not in f:
        if listed or enabled:
            why = "meta/modalities lists tactile" if listed else "meta/collection_config's profile enables tactile"
            problems.append(f"{root}/: missing although {why}")
        return
    if not listed:
        problems.append(f"meta/modalities: expected 'tactile' in the list, since {root}/ is present")
    tactile_dims = dict(dims)
    for node in schema.TACTILE_NODES:
        _check_node(f, "", node, tactile_dims, problems)
    sites = _tactile_sites(f, problems)
    for site in sites:
        for node in schema.TACTILE_SITE_NODES:
            _check_node(f, "", dataclasses.replace(node, path=node.path.format(site=site)), tactile_dims, problems)
    for kind in schema.TACTILE_PER_FRAME:
        group = f.get(f"{root}/{kind}")
        extra = sorted(set(group) - set(sites)) if isinstance(group, h5py.Group) else []
        if extra:
            problems.append(f"{root}/{kind}: sites {extra} are not listed in {root}/site_names")
    try:
        shape = json.loads(f[f"{root}/meta"][()]).get("shape")
    except (KeyError, ValueError, TypeError, AttributeError):
        problems.append(f"{root}/meta: expected a JSON object with the tactile settings")
        return
    stored = [tactile_dims.get("Ht"), tactile_dims.get("Wt")]
    if None not in stored and shape != stored:
        problems.append(f"{root}/meta: shape {shape}, expected the stored tactile grid {stored}")


def _tactile_sites(f: h5py.File, problems: list[str]) -> list[str]:
    path = f"{schema.TACTILE_ROOT}/site_names"
    if path not in f or not isinstance(f[path], h5py.Dataset) or f[path].ndim != 1:
        return []
    sites = [v.decode() if isinstance(v, bytes) else str(v) for v in f[path][()]]
    if not sites or len(set(sites)) != len(sites) or any(not s or "/" in s for s in sites):
        problems.append(f"{path}: expected unique, non-empty site names without '/', got {sites}")
        return []
    return sites


def _collection_profile(f: h5py.File) -> dict:
    """The sensor profile recorded in meta/collection_config ({} when absent or malformed)."""
    try:
        config = json.loads(f["meta/collection_config"][()])
    except (KeyError, ValueError, TypeError):
        return {}
    profile = config.get("profile") if isinstance(config, dict) else None
    return profile if isinstance(profile, dict) else {}


def _profile_enables_tactile(f: h5py.File) -> bool:
    tactile = _collection_profile(f).get("tactile")
    return bool(tactile.get("enabled")) if isinstance(tactile, dict) else False


def _check_labels(f: h5py.File, dims: dict, modalities: list[str], cameras: list[str], problems: list[str]) -> None:
    """Segmentation, 2D/3D boxes and occupancy: each required when meta/modalities or the collection
    profile lists it; one present but not listed in meta/modalities is reported too."""
    profile = _profile_modalities(f)
    present = {"segmentation": any(f"cameras/{cam}/{n.path}" in f for cam in cameras
                                   for n in schema.SEGMENTATION_CAMERA_NODES),
               "box2d": "labels/box2d" in f, "box3d": "labels/box3d" in f, "occupancy": schema.OCCUPANCY_ROOT in f}
    wanted = [m for m in schema.LABEL_MODALITIES if m in modalities or m in profile]
    for m in schema.LABEL_MODALITIES:
        if present[m] and m not in modalities:
            problems.append(f"meta/modalities: expected '{m}' in the list, since its labels are present")
    if not wanted:
        return
    for node in schema.LABEL_ID_NODES:
        _check_node(f, "", node, dict(dims), problems)
    objects = _label_objects(f, problems)
    if "segmentation" in wanted:
        for cam in cameras:
            cam_dims = dict(dims)
            image = next((f[f"cameras/{cam}/{k}"] for k in ("rgb", "depth_m") if f"cameras/{cam}/{k}" in f), None)
            if isinstance(image, h5py.Dataset) and image.ndim >= 3:   # masks match the camera's H, W
                cam_dims.update(H=image.shape[1], W=image.shape[2])
            for node in schema.SEGMENTATION_CAMERA_NODES:
                _check_node(f, f"cameras/{cam}/", node, cam_dims, problems)
    if "box2d" in wanted:
        _check_node(f, "", schema.BOX2D_SEMANTICS_NODE, dict(dims), problems)
        _check_keys(f, "labels/box2d", cameras, "cameras/", problems)
        for cam in cameras:
            _check_keys(f, f"labels/box2d/{cam}", objects, "labels/instances", problems)
            for obj in objects:
                for node in schema.BOX2D_NODES:
                    _check_node(f, f"labels/box2d/{cam}/{obj}/", node, dict(dims), problems)
    if "box3d" in wanted:
        _check_keys(f, "labels/box3d", objects, "labels/instances", problems)
        for obj in objects:
            for node in schema.BOX3D_NODES:
                _check_node(f, f"labels/box3d/{obj}/", node, dict(dims), problems)
    if "occupancy" in wanted:
        occ_dims = dict(dims)
        for node in schema.OCCUPANCY_NODES:
            _check_node(f, "", node, occ_dims, problems)
        root = schema.OCCUPANCY_ROOT
        try:
            shape = [int(v) for v in f[f"{root}/grid_shape"][()]]
            stored = [occ_dims.get(axis) for axis in ("X", "Y", "Z")]
            if None not in stored and shape != stored:
                problems.append(f"{root}/grid_shape: {shape}, expected the stored grid's {stored}")
            json.loads(f[f"{root}/semantics"][()])
        except (KeyError, ValueError, TypeError):
            problems.append(f"{root}/: expected an integer grid_shape [X, Y, Z] and a JSON semantics document")


def _label_objects(f: h5py.File, problems: list[str]) -> list[str]:
    """Object ids of labels/instances, in instance order."""
    try:
        instances = json.loads(f["labels/instances"][()])
        return [instances[k]["name"] for k in sorted(instances, key=int)]
    except (KeyError, ValueError, TypeError):
        problems.append("labels/instances: expected a JSON object {id: {name, category, semantic_id}}")
        return []


def _check_keys(f: h5py.File, group: str, expected: list[str], source: str, problems: list[str]) -> None:
    """A label group's members must be exactly the cameras / objects the episode declares."""
    members = set(f[group]) if isinstance(f.get(group), h5py.Group) else set()
    missing, extra = sorted(set(expected) - members), sorted(members - set(expected))
    if missing:
        problems.append(f"{group}/: missing {missing} (listed in {source})")
    if extra:
        problems.append(f"{group}/: {extra} are not listed in {source}")


def _profile_modalities(f: h5py.File) -> list[str]:
    cameras = _collection_profile(f).get("cameras")
    try:
        return list(cameras.get("modalities", [])) if isinstance(cameras, dict) else []
    except TypeError:
        return []
