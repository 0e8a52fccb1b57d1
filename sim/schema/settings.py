"""Schema of `sim/catalog/settings.yaml`: the paper's task-embodiment settings."""

from __future__ import annotations

from pydantic import Field

from .base import Bool, CatalogModel, Name


class SettingEntry(CatalogModel):
    task: Name
    embodiment: Name
    available: Bool = True      # the task builds and settles on this embodiment


class SettingsFile(CatalogModel):
    paper_settings: list[SettingEntry] = Field(min_length=1)
