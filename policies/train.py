"""Train a learned policy (ACT or Diffusion Policy) from HDF5 episodes into a checkpoint folder.

Deterministic on a CPU: the seed fixes the initial weights, the batches (numpy's generator) and the noise
(torch's), torch runs with deterministic algorithms on the config's thread count, so the same seed, config
and episodes give the same checkpoint bytes.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from episodes.atomic import file_sha256
from policies.checkpoint import save_checkpoint
from policies.config import PolicyConfig
from policies.dataset import PolicyDataset
from policies.interface import ActionSpec, ObservationSpec
from policies.normalize import SCHEMES, Normalizer, image_stats, vector_stats

log = logging.getLogger(__name__)


@dataclass
class TrainResult:
    checkpoint: Path
    steps: int
    final_loss: float
    seconds: float
    steps_per_second: float
    frames: int
    episodes: int
    train_log: list[dict]


def _scene_json(path: Path) -> str:
    from episodes.reader import open_episode
    with open_episode(path) as r:
        return r.static("meta/scene")


def resolve_device(name: str) -> str:
    import torch
    if name == "auto":
        return "cuda" if torch.cuda.is_available() else "cpu"
    if name == "cuda" and not torch.cuda.is_available():
        raise RuntimeError("train.device is 'cuda' but torch sees no GPU; use 'auto' or 'cpu'")
    return name


def seed_everything(seed: int, threads: int) -> None:
    import torch
    torch.manual_seed(seed)
    torch.set_num_threads(threads)
    torch.use_deterministic_algorithms(True)


def training_stats(dataset: PolicyDataset, cfg: PolicyConfig) -> dict:
    return {"scheme": SCHEMES[cfg.policy], "state": vector_stats(dataset.all_states()),
            "action": vector_stats(dataset.all_actions()),
            "images": {v: image_stats(np.concatenate([ep.images[v] for ep in dataset.episodes]))
                       for v in cfg.observation.views}}


def to_model_batch(raw: dict, normalizer: Normalizer, views: tuple[str, ...], device: str = "cpu") -> dict:
    """Numpy samples (uint8 images, raw joints and actions) -> normalized torch tensors for the model."""
    import torch
    out = {"images": normalizer.images(raw["images"], views), "state": normalizer.state(raw["state"])}
    if "tactile" in raw:
        out["tactile"] = normalizer.tactile(raw["tactile"])
    if "actions" in raw:
        out["actions"] = normalizer.action(raw["actions"])
        out["action_pad"] = raw["action_pad"]
    return {k: torch.from_numpy(np.ascontiguousarray(v)).to(device) for k, v in out.items()}


def model_shapes(cfg: PolicyConfig, dataset: PolicyDataset):
    from policies.models.shapes import ModelShapes
    ep, layout = dataset.episodes[0], dataset.layout
    h, w = ep.images[cfg.observation.views[0]].shape[1:3]
    th, tw = next(iter(ep.tactile.values())).shape[1:3] if ep.tactile else (0, 0)
    return ModelShapes(n_views=len(cfg.observation.views), image_height=int(h), image_width=int(w),
                       state_dim=len(layout.state_names), action_dim=len(layout.action_names),
                       n_obs_steps=cfg.observation.n_obs_steps, horizon=cfg.action.horizon,
                       n_tactile=len(layout.tactile_sites), tactile_height=int(th), tactile_width=int(tw))


def build_model(cfg: PolicyConfig, shapes):
    from policies.models import model_class
    entry = model_class(cfg.policy)
    return entry.model_class(cfg.model_config_object(), shapes)


def lr_factor(cfg: PolicyConfig, total_steps: int):
    """The learning-rate multiplier per optimizer step: linear warm-up, then constant or a cosine that
    reaches zero at ``total_steps`` (the run's budget, which `--steps` may set apart from the config's)."""
    t = cfg.train

    def factor(step: int) -> float:
        if step < t.warmup_steps:
            return (step + 1) / t.warmup_steps
        if t.lr_schedule == "cosine":
            progress = (step - t.warmup_steps) / max(1, total_steps - t.warmup_steps)
            return 0.5 * (1.0 + np.cos(np.pi * min(1.0, progress)))
        return 1.0
    return factor


def train_policy(cfg: PolicyConfig, episode_paths: list[Path], out_dir: Path, progress=None,
                 steps: int | None = None) -> TrainResult:
    """Train on the given episodes and write the checkpoint folder. `progress(n)` is called per step;
    `steps` overrides the config's (a quick look), and is recorded."""
    import torch
    from torch.optim.swa_utils import AveragedModel, get_ema_multi_avg_fn

    t = cfg.train
    total = steps or t.steps
    seed_everything(t.seed, t.threads)
    device = resolve_device(t.device)
    paths = sorted(Path(p) for p in episode_paths)
    dataset = PolicyDataset(paths, cfg)
    stats = training_stats(dataset, cfg)
    normalizer = Normalizer(stats["scheme"], stats)
    shapes = model_shapes(cfg, dataset)
    model = build_model(cfg, shapes).to(device)
    ema = AveragedModel(model, multi_avg_fn=get_ema_multi_avg_fn(t.ema_decay)) if t.ema_decay else None
    optimizer = torch.optim.AdamW(model.parameters(), lr=t.lr, weight_decay=t.weight_decay)
    schedule = torch.optim.lr_scheduler.LambdaLR(optimizer, lr_factor(cfg, total))
    rng = np.random.default_rng(t.seed)
    views = cfg.observation.views
    train_log, window, started = [], [], time.perf_counter()
    model.train()
    for step in range(1, total + 1):
        batch = to_model_batch(dataset.batch(rng.integers(0, len(dataset), t.batch_size)), normalizer, views, device)
        loss, parts = model.compute_loss(batch)
        optimizer.zero_grad(set_to_none=True)
        loss.backward()
        if t.grad_clip:
            torch.nn.utils.clip_grad_norm_(model.parameters(), t.grad_clip)
        optimizer.step()
        schedule.step()
        if ema is not None:
            ema.update_parameters(model)
        window.append(parts)
        if step % t.log_every == 0 or step == total:
            row = {"step": step, **{k: float(np.mean([p[k] for p in window])) for k in window[0]}}
            train_log.append(row)
            window = []
        if progress:
            progress(1)
    seconds = time.perf_counter() - started
    final = ema.module if ema is not None else model
    layout = dataset.layout
    spec = ObservationSpec(views=views, width=layout.width or shapes.image_width,
                           height=layout.height or shapes.image_height, rate_hz=layout.rate_hz,
                           n_obs_steps=cfg.observation.n_obs_steps, state_names=layout.state_names,
                           tactile_sites=layout.tactile_sites,
                           tactile_shape=(shapes.tactile_height, shapes.tactile_width),
                           tactile_step=layout.tactile_step, tessellation=layout.tessellation)
    manifest = {"setting": {"task": layout.task, "embodiment": layout.embodiment},
                # each episode's scene sample too: evaluation anchors on the training scenes without the files
                "training_set": [{"episode": p.name, "sha256": file_sha256(p), "scene": _scene_json(p)} for p in paths],
                "profile_hash": layout.profile_hash, "shapes": shapes.__dict__,
                "training": {"steps": total, "seed": t.seed, "threads": t.threads, "device": device,
                             "frames": len(dataset), "final_loss": train_log[-1]["loss"],
                             "torch": torch.__version__}}
    # timings stay out of the checkpoint: its bytes depend on the seed and data only
    save_checkpoint(out_dir, final.state_dict(), cfg, spec, ActionSpec(layout.action_names), stats,
                    manifest, train_log)
    return TrainResult(Path(out_dir), total, train_log[-1]["loss"], seconds, total / max(seconds, 1e-9),
                       len(dataset), len(paths), train_log)
