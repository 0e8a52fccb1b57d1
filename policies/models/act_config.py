"""ACT's model hyper-parameters, apart from the model so that reading a policy config needs no torch."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field, model_validator


class ACTConfig(BaseModel):
    """Model hyper-parameters; the defaults are a tiny config that trains on CPU."""

    model_config = ConfigDict(extra="forbid")

    backbone_width: int = Field(16, gt=0)
    dim_model: int = Field(64, gt=0)
    n_heads: int = Field(4, gt=0)
    dim_feedforward: int = Field(256, gt=0)
    n_encoder_layers: int = Field(2, gt=0)
    n_decoder_layers: int = Field(1, gt=0)
    n_vae_encoder_layers: int = Field(2, gt=0)
    latent_dim: int = Field(16, gt=0)
    dropout: float = Field(0.1, ge=0.0, lt=1.0)
    kl_weight: float = Field(10.0, ge=0.0)
    use_vae: bool = True

    @model_validator(mode="after")
    def _heads_divide_model(self) -> ACTConfig:
        if self.dim_model % self.n_heads:
            raise ValueError(f"dim_model ({self.dim_model}) must be divisible by n_heads ({self.n_heads})")
        return self
