"""Diffusion Policy (Chi et al. 2023, "Diffusion Policy: Visuomotor Policy Learning via Action Diffusion",
RSS 2023), the CNN variant: a 1-D temporal conv U-Net denoises a chunk of ``horizon`` actions, conditioned
by FiLM on the diffusion step and on the observation features of the last ``n_obs_steps`` steps.

Observations: each camera view has its own ResNet-18 (the paper encodes views "independently", with
GroupNorm and a spatial softmax instead of global average pooling), followed by a linear layer; the
proprioceptive state is appended as is, and in the tactile-conditioned variant every tactile site map
goes through one small shared conv encoder. Noise schedules come from ``diffusers`` (DDPM for training,
DDIM or DDPM for sampling). Normalization (images, state, actions to [-1, 1]) happens outside the model.
"""

from __future__ import annotations

import math

import torch
from diffusers import DDIMScheduler, DDPMScheduler
from diffusers.training_utils import EMAModel
from torch import nn

from policies.models.diffusion_config import DiffusionConfig
from policies.models.resnet import ResNet18, conv_output_size
from policies.models.shapes import ModelShapes


# ---------------------------------------------------------------- observation encoder


class SpatialSoftmax(nn.Module):
    """Feature map -> expected (x, y) image position of each of ``n_keypoints`` learned keypoints
    (Levine et al. 2016), which keeps where things are instead of averaging it away."""

    def __init__(self, channels: int, height: int, width: int, n_keypoints: int):
        super().__init__()
        self.keypoints = nn.Conv2d(channels, n_keypoints, 1)
        ys, xs = torch.meshgrid(torch.linspace(-1, 1, height), torch.linspace(-1, 1, width), indexing="ij")
        self.register_buffer("grid", torch.stack([xs.flatten(), ys.flatten()], dim=-1), persistent=False)
        self.out_dim = 2 * n_keypoints

    def forward(self, features: torch.Tensor) -> torch.Tensor:
        attention = self.keypoints(features).flatten(2).softmax(dim=-1)   # (N, K, h*w)
        return (attention @ self.grid).flatten(1)                         # (N, 2K)


class GlobalAvgPool(nn.Module):
    def __init__(self, channels: int):
        super().__init__()
        self.out_dim = channels

    def forward(self, features: torch.Tensor) -> torch.Tensor:
        return features.mean(dim=(2, 3))


class ViewEncoder(nn.Module):
    """One camera view: ResNet-18 -> spatial softmax (or average pool) -> linear feature."""

    def __init__(self, cfg: DiffusionConfig, height: int, width: int):
        super().__init__()
        self.backbone = ResNet18(width=cfg.backbone_width)
        channels = self.backbone.out_channels
        if cfg.image_pooling == "spatial_softmax":
            self.pool = SpatialSoftmax(channels, *ResNet18.output_size(height, width), cfg.n_keypoints)
        else:
            self.pool = GlobalAvgPool(channels)
        self.head = nn.Linear(self.pool.out_dim, cfg.image_feature_dim)

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        return self.head(self.pool(self.backbone(images)))


class TactileEncoder(nn.Module):
    """One tactile site map (1, Ht, Wt) in [0, 1] -> feature; shared by all sites. No normalization layer:
    it would erase how hard a pad is pressed."""

    def __init__(self, height: int, width: int, feature_dim: int, channels: tuple[int, ...] = (8, 16, 32)):
        super().__init__()
        layers, c_in = [], 1
        for c_out in channels:
            layers += [nn.Conv2d(c_in, c_out, 3, stride=2, padding=1), nn.Mish()]
            height, width = conv_output_size(height, 3, 2, 1), conv_output_size(width, 3, 2, 1)
            c_in = c_out
        self.convs = nn.Sequential(*layers)
        self.head = nn.Linear(c_in * height * width, feature_dim)

    def forward(self, maps: torch.Tensor) -> torch.Tensor:
        return self.head(self.convs(maps).flatten(1))


class ObservationEncoder(nn.Module):
    """Batch -> global conditioning (B, n_obs_steps * step_dim), each step [view features, state, tactile]."""

    def __init__(self, cfg: DiffusionConfig, shapes: ModelShapes):
        super().__init__()
        self.shapes = shapes
        self.views = nn.ModuleList(
            ViewEncoder(cfg, shapes.image_height, shapes.image_width) for _ in range(shapes.n_views))
        self.tactile = None
        if shapes.n_tactile > 0:
            self.tactile = TactileEncoder(shapes.tactile_height, shapes.tactile_width, cfg.tactile_feature_dim)
        self.step_dim = (shapes.n_views * cfg.image_feature_dim + shapes.state_dim
                         + shapes.n_tactile * cfg.tactile_feature_dim)
        self.out_dim = shapes.n_obs_steps * self.step_dim

    def forward(self, batch: dict[str, torch.Tensor]) -> torch.Tensor:
        s = self.shapes
        state = batch["state"]
        _expect(state, "state", (s.n_obs_steps, s.state_dim))
        b, t = state.shape[:2]
        parts = []
        if s.n_views:
            images = batch["images"]
            _expect(images, "images", (s.n_obs_steps, s.n_views, 3, s.image_height, s.image_width))
            parts += [view(images[:, :, i].flatten(0, 1)).view(b, t, -1) for i, view in enumerate(self.views)]
        parts.append(state)
        if self.tactile is not None:
            maps = batch["tactile"]
            _expect(maps, "tactile", (s.n_obs_steps, s.n_tactile, s.tactile_height, s.tactile_width))
            parts.append(self.tactile(maps.flatten(0, 2).unsqueeze(1)).view(b, t, -1))
        return torch.cat(parts, dim=-1).flatten(1)


def _expect(x: torch.Tensor, name: str, trailing: tuple[int, ...]) -> None:
    if x.dim() != len(trailing) + 1 or tuple(x.shape[1:]) != trailing:
        raise ValueError(f"batch[{name!r}] has shape {tuple(x.shape)}, expected (B, {', '.join(map(str, trailing))})")


# ---------------------------------------------------------------- 1-D conditional U-Net


def sinusoidal_embedding(steps: torch.Tensor, dim: int) -> torch.Tensor:
    """Transformer-style sine/cosine embedding of the diffusion step: (B,) -> (B, dim)."""
    half = dim // 2
    freqs = torch.exp(-math.log(10000.0) * torch.arange(half, device=steps.device) / max(half - 1, 1))
    angles = steps.float()[:, None] * freqs[None]
    return torch.cat([angles.sin(), angles.cos()], dim=-1)


class ConvNormMish(nn.Sequential):
    def __init__(self, c_in: int, c_out: int, kernel_size: int, n_groups: int):
        super().__init__(nn.Conv1d(c_in, c_out, kernel_size, padding=kernel_size // 2),
                         nn.GroupNorm(n_groups, c_out), nn.Mish())


class FiLMResidualBlock(nn.Module):
    """Two conv blocks; between them the conditioning sets a per-channel scale and shift (FiLM). The
    (scale, shift) projection of all blocks lives in the U-Net, as one matrix product per call."""

    def __init__(self, c_in: int, c_out: int, kernel_size: int, n_groups: int):
        super().__init__()
        self.film_dim = 2 * c_out
        self.conv1 = ConvNormMish(c_in, c_out, kernel_size, n_groups)
        self.conv2 = ConvNormMish(c_out, c_out, kernel_size, n_groups)
        self.residual = nn.Conv1d(c_in, c_out, 1) if c_in != c_out else nn.Identity()

    def forward(self, x: torch.Tensor, film: torch.Tensor) -> torch.Tensor:
        scale, shift = film.unsqueeze(-1).chunk(2, dim=1)
        h = self.conv1(x) * scale + shift
        return self.conv2(h) + self.residual(x)


class ConditionalUnet1D(nn.Module):
    """Denoiser over (B, T, action_dim): ``len(down_dims)`` levels, halving T between levels, with skip
    connections; T is zero-padded on the right to a multiple of 2**(levels - 1) and cropped back.

    Every block's FiLM (scale, shift) is Linear(Mish([step embedding, global cond])), as in DP; all blocks
    share one such matrix here, split by input columns so that the observation part is computed once per
    chunk (``condition``) rather than once per denoising step."""

    def __init__(self, action_dim: int, global_cond_dim: int, cfg: DiffusionConfig):
        super().__init__()
        step_dim = cfg.diffusion_step_embed_dim
        self.step_dim = step_dim
        self.step_mlp = nn.Sequential(nn.Linear(step_dim, 4 * step_dim), nn.Mish(), nn.Linear(4 * step_dim, step_dim))

        def block(c_in: int, c_out: int) -> FiLMResidualBlock:
            return FiLMResidualBlock(c_in, c_out, cfg.kernel_size, cfg.n_groups)

        dims = [action_dim, *cfg.down_dims]
        levels = len(cfg.down_dims)
        self.length_multiple = 2 ** (levels - 1)
        self.down = nn.ModuleList()
        for i, (c_in, c_out) in enumerate(zip(dims[:-1], dims[1:])):
            resample = nn.Conv1d(c_out, c_out, 3, stride=2, padding=1) if i < levels - 1 else nn.Identity()
            self.down.append(nn.ModuleList([block(c_in, c_out), block(c_out, c_out), resample]))
        self.mid = nn.ModuleList([block(dims[-1], dims[-1]), block(dims[-1], dims[-1])])
        self.up = nn.ModuleList()
        for c_in, c_out in reversed(list(zip(dims[1:-1], dims[2:]))):
            # input: the level below (c_out channels) concatenated with this level's skip (c_out channels)
            self.up.append(nn.ModuleList([block(2 * c_out, c_in), block(c_in, c_in),
                                          nn.ConvTranspose1d(c_in, c_in, 4, stride=2, padding=1)]))
        self.final = nn.Sequential(ConvNormMish(dims[1], dims[1], cfg.kernel_size, cfg.n_groups),
                                   nn.Conv1d(dims[1], action_dim, 1))
        blocks = [m for m in self.modules() if isinstance(m, FiLMResidualBlock)]
        self.film_sizes = [b.film_dim for b in blocks]   # modules() order: down, mid, up, as forward uses them
        self.film = nn.Linear(step_dim + global_cond_dim, sum(self.film_sizes))

    def condition(self, global_cond: torch.Tensor) -> torch.Tensor:
        """The observation part of all FiLM projections (B, sum of 2 * channels), fixed during sampling."""
        return nn.functional.linear(nn.functional.mish(global_cond), self.film.weight[:, self.step_dim:])

    def forward(self, sample: torch.Tensor, steps: torch.Tensor, global_film: torch.Tensor) -> torch.Tensor:
        """sample (B, T, action_dim), steps (B,) or scalar, global_film from ``condition``."""
        length = sample.shape[1]
        x = nn.functional.pad(sample.transpose(1, 2), (0, -length % self.length_multiple))
        steps = steps.expand(sample.shape[0]) if steps.dim() == 0 else steps
        step_features = nn.functional.mish(self.step_mlp(sinusoidal_embedding(steps, self.step_dim)))
        film = nn.functional.linear(step_features, self.film.weight[:, :self.step_dim], self.film.bias)
        films = iter((film + global_film).split(self.film_sizes, dim=1))
        skips = []
        for first, second, downsample in self.down:
            x = second(first(x, next(films)), next(films))
            skips.append(x)
            x = downsample(x)
        for mid in self.mid:
            x = mid(x, next(films))
        for first, second, upsample in self.up:
            x = torch.cat([x, skips.pop()], dim=1)
            x = upsample(second(first(x, next(films)), next(films)))
        return self.final(x)[:, :, :length].transpose(1, 2)


# ---------------------------------------------------------------- the policy model


def fill_padded_rows(actions: torch.Tensor, pad: torch.Tensor) -> torch.Tensor:
    """Each padded row takes the value of the nearest valid row (edge padding, as DP's sequence sampler
    does), so whatever a data loader wrote there never reaches the network."""
    horizon = actions.shape[1]
    rows = torch.arange(horizon, device=actions.device)
    distance = (rows[:, None] - rows[None, :]).abs().expand(actions.shape[0], -1, -1)   # (B, row, source)
    distance = distance.masked_fill(pad[:, None, :], horizon + 1)
    source = distance.argmin(dim=-1, keepdim=True).expand(-1, -1, actions.shape[2])
    return torch.gather(actions, 1, source)


class DiffusionModel(nn.Module):
    """Observation encoder + 1-D conditional U-Net + noise schedules; works in normalized action space."""

    def __init__(self, cfg: DiffusionConfig, shapes: ModelShapes):
        super().__init__()
        self.cfg, self.shapes = cfg, shapes
        self.obs_encoder = ObservationEncoder(cfg, shapes)
        self.unet = ConditionalUnet1D(shapes.action_dim, self.obs_encoder.out_dim, cfg)
        schedule = dict(num_train_timesteps=cfg.num_train_timesteps, beta_schedule=cfg.beta_schedule,
                        clip_sample=cfg.clip_sample, prediction_type=cfg.prediction_type)
        self.noise_scheduler = DDPMScheduler(**schedule)
        # same betas; set_timesteps is called on every prediction, so reusing it keeps calls independent
        self.inference_scheduler = (DDIMScheduler if cfg.inference_scheduler == "ddim" else DDPMScheduler)(**schedule)

    def compute_loss(self, batch: dict[str, torch.Tensor]) -> tuple[torch.Tensor, dict[str, float]]:
        """Denoising loss: noise and diffusion steps come from torch's global RNG; padded rows are masked."""
        actions = batch["actions"]
        pad = batch.get("action_pad")
        pad = torch.zeros(actions.shape[:2], dtype=torch.bool, device=actions.device) if pad is None else pad.bool()
        if pad.any():
            actions = fill_padded_rows(actions, pad)
        global_film = self.unet.condition(self.obs_encoder(batch))
        noise = torch.randn_like(actions)
        steps = torch.randint(0, self.cfg.num_train_timesteps, (actions.shape[0],), device=actions.device)
        predicted = self.unet(self.noise_scheduler.add_noise(actions, noise, steps), steps, global_film)
        target = noise if self.cfg.prediction_type == "epsilon" else actions
        valid = (~pad).unsqueeze(-1).to(predicted.dtype)
        squared_error = (predicted - target).square() * valid
        mse = squared_error.sum() / (valid.sum() * actions.shape[2]).clamp_min(1.0)
        value = mse.item()
        return mse, {"mse": value, "loss": value}

    @torch.no_grad()
    def predict_chunk(self, batch: dict[str, torch.Tensor], generator: torch.Generator | None = None) -> torch.Tensor:
        """Sample a (B, horizon, action_dim) chunk in normalized action space, starting from noise drawn
        with ``generator``."""
        global_film = self.unet.condition(self.obs_encoder(batch))
        shape = (global_film.shape[0], self.shapes.horizon, self.shapes.action_dim)
        device = global_film.device
        noise_device = generator.device if generator is not None else device
        sample = torch.randn(shape, generator=generator, device=noise_device, dtype=global_film.dtype).to(device)
        scheduler = self.inference_scheduler
        scheduler.set_timesteps(self.cfg.num_inference_steps, device=device)
        for step in scheduler.timesteps:
            predicted = self.unet(sample, step, global_film)
            sample = scheduler.step(predicted, step, sample, generator=generator).prev_sample
        return sample


class EMA:
    """Exponential moving average of a model's parameters (DP evaluates with the EMA weights), kept by
    diffusers' EMAModel. Its decay ramps as min(decay, (1 + n) / (10 + n)) over the first n updates.
    Buffers are not averaged (the models here have only constant ones)."""

    def __init__(self, model: nn.Module, decay: float):
        self._ema = EMAModel(model.parameters(), decay=decay)

    def update(self, model: nn.Module) -> None:
        self._ema.step(model.parameters())

    def copy_to(self, model: nn.Module) -> None:
        self._ema.copy_to(model.parameters())

    def to(self, device: torch.device | str) -> "EMA":
        self._ema.to(device=device)
        return self

    def state_dict(self) -> dict:
        return self._ema.state_dict()

    def load_state_dict(self, state: dict) -> None:
        self._ema.load_state_dict(state)
