"""Training samples from HDF5 episodes: observation windows and action chunks with padding masks.

For the newest observation at frame k the sample holds the views, the joint positions (and TacMap images
when the policy reads them) of frames k - n_obs + 1 .. k (the first frame repeated before the start), and
the actions of frames k + start .. k + start + horizon - 1; rows outside the episode repeat its first or
last action and are marked in `action_pad`, so the loss ignores them. Frame k's action is the joint target
that produced frame k's state, so the next frame's action (start 1) is what a policy observing frame k
must command.

Episodes are read whole into memory as uint8 images: CPU-sized data (a few hundred frames of four 64x48
views per episode). Paper-sized views (288x216) over hundreds of episodes would need reading by chunk.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from episodes import schema
from episodes.reader import open_episode
from policies.config import PolicyConfig
from sim.errors import SpecError


@dataclass
class EpisodeArrays:
    name: str
    images: dict[str, np.ndarray]        # view -> uint8 [T, H, W, 3]
    state: np.ndarray                    # float32 [T, J]
    actions: np.ndarray                  # float32 [T, A]
    tactile: dict[str, np.ndarray]       # site -> uint8 [T, Ht, Wt]

    @property
    def num_frames(self) -> int:
        return int(self.state.shape[0])


@dataclass(frozen=True)
class EpisodeLayout:
    """What every training episode of one policy must agree on."""

    task: str
    embodiment: str
    state_names: tuple[str, ...]
    action_names: tuple[str, ...]
    tactile_sites: tuple[str, ...]
    width: int
    height: int
    rate_hz: int
    tactile_step: int
    profile_hash: str
    tessellation: tuple[int, int] | None = None


def read_episode(path: Path, cfg: PolicyConfig) -> tuple[EpisodeArrays, EpisodeLayout]:
    """One episode's policy inputs; SpecError naming the file and the dataset when one is missing."""
    with open_episode(path) as r:
        collection = r.meta("collection_config")
        profile = collection.get("profile", {}) if isinstance(collection, dict) else {}
        images = {}
        for view in cfg.observation.views:
            key = f"cameras/{view}/rgb"
            if key not in r:
                raise SpecError(path, key, f"RGB frames of view '{view}' (render the episodes under sensor profile "
                                           f"'{cfg.observation.sensor_profile}')")
            images[view] = r.read(key)
        sites = tuple(r.tactile_sites) if cfg.observation.tactile else ()
        if cfg.observation.tactile and not sites:
            raise SpecError(path, schema.TACTILE_ROOT, "TacMap frames (the config reads tactile)")
        tactile = {s: r.read(schema.tactile_path("tacmap", s)) for s in sites}
        cams = profile.get("cameras", {})
        layout = EpisodeLayout(
            task=r.meta("task"), embodiment=r.meta("embodiment"),
            state_names=tuple(r.static("robot/joint_names")), action_names=tuple(r.static("action/names")),
            tactile_sites=sites, width=int(cams.get("width", 0)), height=int(cams.get("height", 0)),
            rate_hz=int(profile.get("rate_hz", 0)), tactile_step=int(profile.get("tactile", {}).get("step", 1)),
            profile_hash=str(collection.get("profile_hash", "")),
            tessellation=tuple(cams["tessellation"]) if cams.get("tessellation") else None)
        arrays = EpisodeArrays(Path(path).stem, images, r.read("robot/qpos").astype(np.float32),
                               r.read("action/action").astype(np.float32), tactile)
    if not (np.isfinite(arrays.state).all() and np.isfinite(arrays.actions).all()):
        raise SpecError(path, "robot/qpos, action/action", "finite joint positions and actions")
    return arrays, layout


class PolicyDataset:
    """All frames of the given episodes as training samples; `batch(indices)` gives numpy arrays."""

    def __init__(self, paths: list[Path], cfg: PolicyConfig):
        if not paths:
            raise ValueError("no training episodes: materialize or record episodes of the setting first")
        self.cfg = cfg
        self.episodes: list[EpisodeArrays] = []
        self.layout: EpisodeLayout | None = None
        for path in paths:
            arrays, layout = read_episode(Path(path), cfg)
            if self.layout is None:
                self.layout = layout
            elif layout != self.layout:
                raise SpecError(path, "meta", f"the same task, embodiment, joints, actions and sensor profile as "
                                              f"{Path(paths[0]).name} ({_difference(self.layout, layout)})")
            self.episodes.append(arrays)
        # (episode, frame) of every sample
        self.index = np.array([(e, k) for e, ep in enumerate(self.episodes) for k in range(ep.num_frames)],
                              dtype=np.int64)

    def __len__(self) -> int:
        return int(self.index.shape[0])

    @property
    def num_frames(self) -> int:
        return len(self)

    def batch(self, sample_ids: np.ndarray) -> dict[str, np.ndarray]:
        """images uint8 [B, n_obs, V, H, W, 3], state float32 [B, n_obs, J], tactile uint8 [B, n_obs, S, Ht, Wt]
        (when read), actions float32 [B, horizon, A], action_pad bool [B, horizon]."""
        obs, act = self.cfg.observation, self.cfg.action
        rows = {"images": [], "state": [], "tactile": [], "actions": [], "action_pad": []}
        for e, k in self.index[sample_ids]:
            ep = self.episodes[e]
            frames = np.clip(np.arange(k - obs.n_obs_steps + 1, k + 1), 0, None)
            targets = np.arange(k + act.start, k + act.start + act.horizon)
            rows["images"].append(np.stack([ep.images[v][frames] for v in obs.views], axis=1))
            rows["state"].append(ep.state[frames])
            if ep.tactile:
                rows["tactile"].append(np.stack([ep.tactile[s][frames] for s in self.layout.tactile_sites], axis=1))
            rows["actions"].append(ep.actions[np.clip(targets, 0, ep.num_frames - 1)])
            rows["action_pad"].append((targets < 0) | (targets >= ep.num_frames))
        return {key: np.stack(value) for key, value in rows.items() if value}

    def all_states(self) -> np.ndarray:
        return np.concatenate([ep.state for ep in self.episodes])

    def all_actions(self) -> np.ndarray:
        return np.concatenate([ep.actions for ep in self.episodes])


def _difference(a: EpisodeLayout, b: EpisodeLayout) -> str:
    return ", ".join(f"{f}: {getattr(a, f)!r} vs {getattr(b, f)!r}" for f in a.__dataclass_fields__
                     if getattr(a, f) != getattr(b, f))
