"""Tests that need a catalog file with one field changed: the edited copy is written to a temporary
folder that the description loader reads instead, with its cache cleared on the way in and out."""

import contextlib

import yaml

from sim.embodiment import catalog_paths, description

# kind -> (the module attribute naming the folder, the cached loader that reads it)
KINDS = {"arms": ("ARMS_DIR", "load_arm"), "hands": ("HANDS_DIR", "load_hand"),
         "embodiments": ("EMBODIMENTS_DIR", "load_embodiment")}


@contextlib.contextmanager
def edited_catalog_file(monkeypatch, folder, kind: str, name: str, edit):
    """Inside the block, ``description``'s loader for ``kind`` reads ``name``'s file as changed by
    ``edit(raw)`` (which edits the parsed YAML in place); yields the edited file's path."""
    dir_attr, loader_name = KINDS[kind]
    loader = getattr(description, loader_name)
    raw = yaml.safe_load((getattr(description, dir_attr) / f"{name}.yaml").read_text())
    edit(raw)
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(raw))
    with monkeypatch.context() as patch:
        patch.setattr(catalog_paths, dir_attr, folder)     # the loaders read the folder from there
        loader.cache_clear()
        try:
            yield path
        finally:
            loader.cache_clear()
