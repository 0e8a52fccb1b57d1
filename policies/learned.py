"""A trained checkpoint (ACT or Diffusion Policy) behind the policy interface.

`act` normalises the observation window with the checkpoint's statistics, predicts a chunk and returns
joint targets. ACT re-plans every step and fuses the chunks that cover the current step by temporal
ensembling (weights exp(-m i), the oldest prediction first, as in the ACT paper); Diffusion Policy returns
`execute` rows from `first_executed` (receding horizon), which the runner pops one per step.
"""

from __future__ import annotations

import inspect
from collections import deque
from pathlib import Path

import numpy as np

from policies.checkpoint import Checkpoint, load_checkpoint
from policies.interface import ActionSpec, ObservationSpec, PolicyError
from policies.normalize import Normalizer
from policies.train import build_model, to_model_batch


class TemporalEnsembler:
    """Fuses every stored chunk's prediction for the current step."""

    def __init__(self, coeff: float):
        self.coeff = coeff
        self.chunks: deque[np.ndarray] = deque()     # oldest first; row 0 of each is the current step

    def reset(self) -> None:
        self.chunks.clear()

    def update(self, chunk: np.ndarray) -> np.ndarray:
        self.chunks.append(chunk)
        rows = np.stack([c[0] for c in self.chunks])
        weights = np.exp(-self.coeff * np.arange(len(rows)))
        fused = (weights[:, None] * rows).sum(0) / weights.sum()
        # advance: each chunk's next row is the next step's prediction; drop spent chunks
        self.chunks = deque(c[1:] for c in self.chunks if len(c) > 1)
        return fused


class LearnedPolicy:
    """Any checkpoint of `policies/train.py` as a `Policy`."""

    def __init__(self, checkpoint: Checkpoint | str | Path, device: str = "cpu", threads: int = 1):
        import torch

        # one evaluation process per core: torch's own threads would spin against the renderer and the
        # other process (measured: 6 ms a query on one thread, 770 ms on two threads of a busy machine)
        torch.set_num_threads(threads)

        from policies.models.shapes import ModelShapes

        ckpt = checkpoint if isinstance(checkpoint, Checkpoint) else load_checkpoint(checkpoint)
        self.checkpoint = ckpt
        cfg = ckpt.config
        self.name = f"{cfg.policy}_{cfg.name}"
        self.observation_spec: ObservationSpec = ckpt.observation_spec
        self.action_spec: ActionSpec = ckpt.action_spec
        self.normalizer = Normalizer(ckpt.stats["scheme"], ckpt.stats)
        self.model = build_model(cfg, ModelShapes(**ckpt.manifest["shapes"]))
        missing, unexpected = self.model.load_state_dict(ckpt.state_dict, strict=False)
        if missing or unexpected:
            raise ValueError(f"{ckpt.path}: weights do not fit the {cfg.policy} model of its config "
                             f"(missing {missing[:3]}, unexpected {unexpected[:3]})")
        self.model.to(device).eval()
        self.device = device
        self.action = cfg.action
        self.actions_per_query = cfg.action.execute
        self.ensembler = (TemporalEnsembler(cfg.action.temporal_ensemble_coeff)
                          if cfg.action.temporal_ensemble_coeff is not None else None)
        self.generator = torch.Generator().manual_seed(0)
        # a sampling policy (diffusion) draws its noise from the episode's seed, so rollouts repeat
        self.takes_generator = "generator" in inspect.signature(self.model.predict_chunk).parameters

    def reset(self, seed: int, instruction: str) -> None:
        self.generator.manual_seed(int(seed))
        if self.ensembler:
            self.ensembler.reset()

    def _batch(self, observation: dict) -> dict:
        spec = self.observation_spec
        try:
            raw = {"images": np.stack([observation["images"][v] for v in spec.views], axis=1)[None],
                   "state": np.asarray(observation["state"], np.float32)[None]}
            if spec.tactile_sites:
                raw["tactile"] = np.stack([observation["tactile"][s] for s in spec.tactile_sites], axis=1)[None]
        except KeyError as exc:
            raise PolicyError(f"{self.name}: the observation lacks {exc} that the policy's spec names") from exc
        return to_model_batch(raw, self.normalizer, spec.views, self.device)

    def act(self, observation: dict) -> np.ndarray:
        import torch

        batch = self._batch(observation)
        with torch.inference_mode():
            if self.takes_generator:
                chunk = self.model.predict_chunk(batch, generator=self.generator)
            else:
                chunk = self.model.predict_chunk(batch)
        chunk = self.normalizer.unnormalize_action(chunk[0].cpu().numpy())
        if self.ensembler is not None:
            return self.ensembler.update(chunk)[None]
        first = self.action.first_executed
        return chunk[first: first + self.action.execute]
