"""ACT: Action Chunking with Transformers (Zhao et al. 2023, "Learning Fine-Grained Bimanual
Manipulation with Low-Cost Hardware"), a conditional VAE whose decoder is a DETR-style transformer.

The observation (latent token, state token, optional tactile tokens, image tokens from a shared
ResNet-18) is encoded by a transformer encoder; ``horizon`` learned queries cross-attend to it and a
linear head gives the action chunk. While computing the loss, a second transformer encoder (the CVAE
encoder) reads [CLS, state, actions] and gives the posterior over the style latent; when predicting,
the latent is the prior mean, zeros. Transformer layers are pre-norm (more stable for the small,
from-scratch models trained here than the paper's post-norm), with positions added to queries and
keys at every layer as in DETR. Inputs and outputs are in normalized space; normalization is done
outside the model.
"""

from __future__ import annotations

import math

import torch
import torch.nn.functional as F
from torch import nn

from policies.models.act_config import ACTConfig
from policies.models.resnet import ResNet18, make_norm
from policies.models.shapes import ModelShapes


def sinusoid_table(n_positions: int, dim: int) -> torch.Tensor:
    """(n_positions, dim) fixed sin/cos position codes, interleaved; any ``dim`` (odd ones truncated)."""
    n_freqs = (dim + 1) // 2
    freqs = torch.exp(-math.log(10000.0) * torch.arange(n_freqs, dtype=torch.float64) / n_freqs)
    angles = torch.arange(n_positions, dtype=torch.float64)[:, None] * freqs[None, :]
    table = torch.stack([angles.sin(), angles.cos()], dim=-1).flatten(1)[:, :dim]
    return table.float()


def sinusoid_table_2d(height: int, width: int, dim: int) -> torch.Tensor:
    """(height * width, dim) position codes of a feature map, row-major: half the channels code the
    row, the other half the column."""
    dim_rows = dim // 2
    rows = sinusoid_table(height, dim_rows)[:, None, :].expand(height, width, dim_rows)
    cols = sinusoid_table(width, dim - dim_rows)[None, :, :].expand(height, width, dim - dim_rows)
    return torch.cat([rows, cols], dim=-1).reshape(height * width, dim)


class Attention(nn.Module):
    """Multi-head attention; ``key_padding_mask`` is True where a key must be ignored."""

    def __init__(self, dim: int, n_heads: int, dropout: float):
        super().__init__()
        self.n_heads = n_heads
        self.dropout = dropout
        self.q_proj, self.k_proj, self.v_proj, self.out_proj = (nn.Linear(dim, dim) for _ in range(4))

    def _split_heads(self, x: torch.Tensor) -> torch.Tensor:
        b, n, d = x.shape
        return x.view(b, n, self.n_heads, d // self.n_heads).transpose(1, 2)

    def forward(self, query, key, value, key_padding_mask: torch.Tensor | None = None) -> torch.Tensor:
        q = self._split_heads(self.q_proj(query))
        k = self._split_heads(self.k_proj(key))
        v = self._split_heads(self.v_proj(value))
        attend = None if key_padding_mask is None else ~key_padding_mask[:, None, None, :]
        dropout = self.dropout if self.training else 0.0
        out = F.scaled_dot_product_attention(q, k, v, attn_mask=attend, dropout_p=dropout)
        return self.out_proj(out.transpose(1, 2).flatten(2))


def feed_forward(dim: int, hidden: int, dropout: float) -> nn.Sequential:
    return nn.Sequential(nn.Linear(dim, hidden), nn.GELU(), nn.Dropout(dropout), nn.Linear(hidden, dim))


class EncoderLayer(nn.Module):
    def __init__(self, cfg: ACTConfig):
        super().__init__()
        self.norm1, self.norm2 = nn.LayerNorm(cfg.dim_model), nn.LayerNorm(cfg.dim_model)
        self.attn = Attention(cfg.dim_model, cfg.n_heads, cfg.dropout)
        self.ff = feed_forward(cfg.dim_model, cfg.dim_feedforward, cfg.dropout)
        self.drop = nn.Dropout(cfg.dropout)

    def forward(self, x, pos, key_padding_mask=None):
        h = self.norm1(x)
        x = x + self.drop(self.attn(h + pos, h + pos, h, key_padding_mask))
        return x + self.drop(self.ff(self.norm2(x)))


class DecoderLayer(nn.Module):
    def __init__(self, cfg: ACTConfig):
        super().__init__()
        self.norm1, self.norm2, self.norm3 = (nn.LayerNorm(cfg.dim_model) for _ in range(3))
        self.self_attn = Attention(cfg.dim_model, cfg.n_heads, cfg.dropout)
        self.cross_attn = Attention(cfg.dim_model, cfg.n_heads, cfg.dropout)
        self.ff = feed_forward(cfg.dim_model, cfg.dim_feedforward, cfg.dropout)
        self.drop = nn.Dropout(cfg.dropout)

    def forward(self, x, query_pos, memory, memory_pos):
        h = self.norm1(x)
        x = x + self.drop(self.self_attn(h + query_pos, h + query_pos, h))
        h = self.norm2(x)
        x = x + self.drop(self.cross_attn(h + query_pos, memory + memory_pos, memory))
        return x + self.drop(self.ff(self.norm3(x)))


class TransformerEncoder(nn.Module):
    def __init__(self, cfg: ACTConfig, n_layers: int):
        super().__init__()
        self.layers = nn.ModuleList(EncoderLayer(cfg) for _ in range(n_layers))
        self.norm = nn.LayerNorm(cfg.dim_model)  # pre-norm layers leave the residual stream unnormalized

    def forward(self, x, pos, key_padding_mask=None):
        for layer in self.layers:
            x = layer(x, pos, key_padding_mask)
        return self.norm(x)


class TransformerDecoder(nn.Module):
    def __init__(self, cfg: ACTConfig):
        super().__init__()
        self.layers = nn.ModuleList(DecoderLayer(cfg) for _ in range(cfg.n_decoder_layers))
        self.norm = nn.LayerNorm(cfg.dim_model)

    def forward(self, x, query_pos, memory, memory_pos):
        for layer in self.layers:
            x = layer(x, query_pos, memory, memory_pos)
        return self.norm(x)


class TactileEncoder(nn.Module):
    """One token per tactile site: three small convs, then mean- and max-pooled (a light touch and a
    single sharp contact both register) and projected to ``dim``."""

    def __init__(self, dim: int, channels: int = 32):
        super().__init__()
        layers: list[nn.Module] = []
        in_channels = 1
        for out_channels, stride in ((channels // 2, 2), (channels, 2), (channels, 1)):
            layers += [nn.Conv2d(in_channels, out_channels, 3, stride=stride, padding=1),
                       make_norm("group", out_channels), nn.ReLU(inplace=True)]
            in_channels = out_channels
        self.convs = nn.Sequential(*layers)
        self.proj = nn.Linear(2 * channels, dim)

    def forward(self, maps: torch.Tensor) -> torch.Tensor:
        """(B, S, Ht, Wt) -> (B, S, dim)."""
        b, s, h, w = maps.shape
        features = self.convs(maps.reshape(b * s, 1, h, w)).flatten(2)
        pooled = torch.cat([features.mean(-1), features.amax(-1)], dim=-1)
        return self.proj(pooled).view(b, s, -1)


class CVAEEncoder(nn.Module):
    """Posterior q(z | state, actions): a transformer over [CLS, state, action_1..horizon]; padded
    action rows are masked out as keys."""

    def __init__(self, cfg: ACTConfig, shapes: ModelShapes):
        super().__init__()
        self.cls = nn.Parameter(torch.randn(1, 1, cfg.dim_model))
        self.state_proj = nn.Linear(shapes.state_dim, cfg.dim_model)
        self.action_proj = nn.Linear(shapes.action_dim, cfg.dim_model)
        self.register_buffer("pos", sinusoid_table(2 + shapes.horizon, cfg.dim_model)[None], persistent=False)
        self.encoder = TransformerEncoder(cfg, cfg.n_vae_encoder_layers)
        self.to_latent = nn.Linear(cfg.dim_model, 2 * cfg.latent_dim)

    def forward(self, state, actions, action_pad) -> tuple[torch.Tensor, torch.Tensor]:
        b = state.shape[0]
        tokens = torch.cat(
            [self.cls.expand(b, -1, -1), self.state_proj(state)[:, None], self.action_proj(actions)], dim=1
        )
        pad = torch.cat([torch.zeros(b, 2, dtype=torch.bool, device=state.device), action_pad], dim=1)
        cls_out = self.encoder(tokens, self.pos, pad)[:, 0]
        mu, logvar = self.to_latent(cls_out).chunk(2, dim=-1)
        return mu, logvar


class ACTModel(nn.Module):
    """ACT for ``shapes``; see the module docstring. Batches are dicts of tensors:
    ``images`` (B, T, V, 3, H, W), ``state`` (B, T, state_dim), ``tactile`` (B, T, S, Ht, Wt) when
    ``shapes.n_tactile`` > 0, and for the loss ``actions`` (B, horizon, action_dim) and ``action_pad``
    (B, horizon), True on padded rows. Only the last observation step (T - 1) is used."""

    def __init__(self, cfg: ACTConfig, shapes: ModelShapes):
        super().__init__()
        if shapes.n_views < 1:
            raise ValueError("ACT needs at least one camera view")
        self.cfg, self.shapes = cfg, shapes
        dim = cfg.dim_model

        self.backbone = ResNet18(width=cfg.backbone_width)
        self.image_proj = nn.Conv2d(self.backbone.out_channels, dim, 1)
        self.feature_size = ResNet18.output_size(shapes.image_height, shapes.image_width)
        self.register_buffer("image_pos", sinusoid_table_2d(*self.feature_size, dim), persistent=False)
        self.view_embed = nn.Parameter(torch.randn(shapes.n_views, 1, dim))

        self.latent_proj = nn.Linear(cfg.latent_dim, dim)
        self.state_proj = nn.Linear(shapes.state_dim, dim)
        self.latent_state_embed = nn.Parameter(torch.randn(2, dim))
        if shapes.n_tactile > 0:
            self.tactile_encoder = TactileEncoder(dim)
            self.tactile_embed = nn.Parameter(torch.randn(shapes.n_tactile, dim))

        self.encoder = TransformerEncoder(cfg, cfg.n_encoder_layers)
        self.decoder = TransformerDecoder(cfg)
        # Learned embeddings start at N(0, 1), as nn.Embedding does: the decoder stream starts at zeros,
        # so these are all that tells the horizon steps apart (0.02-scale ones stalled overfitting).
        self.query_embed = nn.Parameter(torch.randn(shapes.horizon, dim))
        self.action_head = nn.Linear(dim, shapes.action_dim)
        self.vae_encoder = CVAEEncoder(cfg, shapes) if cfg.use_vae else None

    def _encode_observation(self, batch: dict[str, torch.Tensor], latent: torch.Tensor):
        images = batch["images"][:, -1]
        b = images.shape[0]
        features = self.image_proj(self.backbone(images.flatten(0, 1)))
        if tuple(features.shape[-2:]) != self.feature_size:
            raise ValueError(f"images of {tuple(images.shape[-2:])} do not match the model's "
                             f"{(self.shapes.image_height, self.shapes.image_width)}")
        # (B*V, D, h, w) -> (B, V*h*w, D), view-major like the position codes below
        image_tokens = features.flatten(2).transpose(1, 2).reshape(b, -1, self.cfg.dim_model)
        image_pos = (self.image_pos[None] + self.view_embed).flatten(0, 1)

        tokens = [self.latent_proj(latent)[:, None], self.state_proj(batch["state"][:, -1])[:, None]]
        pos = [self.latent_state_embed]
        if self.shapes.n_tactile > 0:
            tokens.append(self.tactile_encoder(batch["tactile"][:, -1]))
            pos.append(self.tactile_embed)
        tokens.append(image_tokens)
        pos.append(image_pos)
        memory_pos = torch.cat(pos)[None]
        return self.encoder(torch.cat(tokens, dim=1), memory_pos), memory_pos

    def forward(self, batch: dict[str, torch.Tensor], latent: torch.Tensor) -> torch.Tensor:
        """Action chunk (B, horizon, action_dim) for the observation in ``batch`` and ``latent`` (B, latent_dim)."""
        memory, memory_pos = self._encode_observation(batch, latent)
        queries = torch.zeros(latent.shape[0], self.shapes.horizon, self.cfg.dim_model, device=latent.device)
        return self.action_head(self.decoder(queries, self.query_embed[None], memory, memory_pos))

    def compute_loss(self, batch: dict[str, torch.Tensor]) -> tuple[torch.Tensor, dict[str, float]]:
        """L1 over non-padded action rows, plus ``kl_weight`` * KL(q(z | state, actions) || N(0, I))
        with the VAE. The posterior is used whenever the VAE is on, also in eval mode (validation)."""
        actions, pad = batch["actions"], batch["action_pad"]
        state = batch["state"][:, -1]
        if self.vae_encoder is not None:
            # Zeroed so that padded rows (masked as keys anyway) cannot carry NaN into the CLS token.
            mu, logvar = self.vae_encoder(state, actions.masked_fill(pad[..., None], 0.0), pad)
            latent = mu + torch.exp(0.5 * logvar) * torch.randn_like(mu)
            kl = (-0.5 * (1 + logvar - mu.pow(2) - logvar.exp())).sum(-1).mean()
        else:
            latent = state.new_zeros(state.shape[0], self.cfg.latent_dim)
            kl = state.new_zeros(())
        predicted = self(batch, latent)
        valid = ~pad
        abs_error = torch.where(valid[..., None], (predicted - actions).abs(), 0.0)
        l1 = abs_error.sum() / (valid.sum().clamp(min=1) * actions.shape[-1])
        loss = l1 + self.cfg.kl_weight * kl
        return loss, {"l1": l1.item(), "kl": kl.item(), "loss": loss.item()}

    @torch.no_grad()
    def predict_chunk(self, batch: dict[str, torch.Tensor]) -> torch.Tensor:
        """(B, horizon, action_dim) normalized actions from images, state (and tactile), with the prior mean latent."""
        b = batch["state"].shape[0]
        latent = batch["state"].new_zeros(b, self.cfg.latent_dim)
        return self(batch, latent)
