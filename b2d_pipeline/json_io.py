"""An IO manager for the small records ops hand each other (paths, hashes, counts, errors) as JSON.

Dagster's default IO manager pickles outputs to disk and unpickles them in the next step; nothing in
b2d loads pickles from disk, and the fan-out ops only pass JSON-shaped values anyway. Files are written
to a temporary name and renamed, under the run's id, so a killed step never leaves a half-written one.
"""

from __future__ import annotations

import json
from pathlib import Path

import dagster as dg

from episodes.atomic import atomic_path


class JsonIOManager(dg.ConfigurableIOManager):
    base_dir: str

    def _path(self, context) -> Path:
        parts = context.get_asset_identifier() if context.has_asset_key else context.get_identifier()
        return Path(self.base_dir, *parts).with_suffix(".json")

    def handle_output(self, context: dg.OutputContext, obj) -> None:
        if obj is None:
            return
        path = self._path(context)
        path.parent.mkdir(parents=True, exist_ok=True)
        try:
            text = json.dumps(obj, sort_keys=True, indent=1)
        except TypeError as exc:
            raise TypeError(f"output {context.name!r} of step {context.step_key!r} is not JSON-serializable: "
                            f"{exc}") from exc
        with atomic_path(path) as tmp:
            Path(tmp).write_text(text)

    def load_input(self, context: dg.InputContext):
        return json.loads(self._path(context.upstream_output).read_text())
