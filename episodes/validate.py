"""Check an HDF5 episode against the schema; report every missing or malformed node."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import h5py
import numpy as np

from episodes import schema

_KIND = {"uint8": "u", "float32": "f", "float64": "f", "int64": "i", "bool": "b", "str": "O"}


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
    if node.dtype and kind != _KIND[node.dtype] or (node.dtype in ("uint8", "float32") and obj.dtype != np.dtype(node.dtype)):
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


def validate_episode(path: str | Path) -> list[str]:
    """Return the list of problems (empty when the episode matches the schema)."""
    path = Path(path)
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        return [f"{path}: not a readable HDF5 file ({exc})"]
    problems: list[str] = []
    with f:
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
        for obj in (list(f["objects"].keys()) if "objects" in f else []):
            for node in schema.OBJECT_NODES:
                _check_node(f, f"objects/{obj}/", node, dict(dims), problems)
        if "metrics/episode" in f:
            try:
                json.loads(f["metrics/episode"][()])
            except (ValueError, TypeError):
                problems.append("metrics/episode: expected a JSON document")
        for name, ds in (f["metrics/timeseries"].items() if "metrics/timeseries" in f else []):
            if not isinstance(ds, h5py.Dataset):
                problems.append(f"metrics/timeseries/{name}: expected a dataset")
    return problems


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


def _profile_enables_tactile(f: h5py.File) -> bool:
    try:
        config = json.loads(f["meta/collection_config"][()])
        return bool(config["profile"]["tactile"]["enabled"])
    except (KeyError, ValueError, TypeError):
        return False
