"""One schema layer for the catalog files: a pydantic model per kind (`base.CatalogModel`: unknown keys,
wrong types and out-of-range values refused, the file and the field named). Loaders in `sim.registry`,
`sim.tasks` and `sim.embodiment` validate with these before they build their objects."""

from .base import CatalogModel, load, read_yaml, validate

__all__ = ["CatalogModel", "load", "read_yaml", "validate"]
