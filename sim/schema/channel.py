"""Schema of `sim/catalog/channels/<name>.yaml`: a generalization channel."""

from __future__ import annotations

from .base import Bool, CatalogModel, Name


class ChannelFile(CatalogModel):
    name: Name
    paper_name: Name
    anchored: Bool
    resample_invariance: Bool
    resample_equivariance: Bool
