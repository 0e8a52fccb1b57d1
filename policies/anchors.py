"""Evaluation anchors: the scene samples that anchored channels start from (paper: matched episodes)."""

from __future__ import annotations

import json
from pathlib import Path

from episodes.reader import EpisodeReader
from sim.scene.sample import SceneSample


def episode_anchors(paths: list[Path]) -> list[tuple[str, SceneSample]]:
    """(episode name, scene sample) of recorded HDF5 episodes, in file order."""
    anchors = []
    for path in sorted(paths):
        with EpisodeReader(path) as r:
            anchors.append((Path(path).stem, SceneSample.from_json(json.dumps(r.meta("scene")))))
    return anchors


def checkpoint_anchors(manifest: dict) -> list[tuple[str, SceneSample]]:
    """The training scenes a checkpoint recorded (its episodes' scene samples)."""
    return [(Path(e["episode"]).stem, SceneSample.from_json(e["scene"])) for e in manifest.get("training_set", [])
            if e.get("scene")]
