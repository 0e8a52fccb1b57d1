"""The episode store: where every stage's files live, keyed so nothing is ever overwritten by a
different configuration (renders and episodes by sensor-profile hash)."""

from __future__ import annotations

from pathlib import Path

import dagster as dg

from episodes.atomic import file_sha256


class EpisodeStore(dg.ConfigurableResource):
    """Local filesystem store. A remote store (object storage) implements the same paths."""

    data_root: str

    @property
    def root(self) -> Path:
        return Path(self.data_root)

    def raw_dir(self, setting: str) -> Path:
        return self.root / "raw" / setting

    def teleop_dir(self, setting: str) -> Path:
        """Where `b2d teleop` writes a setting's live recordings by default (the sensor watches it)."""
        return self.root / "teleop" / setting

    def replay_dir(self, setting: str) -> Path:
        return self.root / "replays" / setting

    def render_dir(self, profile_hash: str, setting: str) -> Path:
        return self.root / "renders" / profile_hash / setting

    def episode_dir(self, profile_hash: str, setting: str) -> Path:
        return self.root / "episodes" / profile_hash / setting

    def checkpoint_dir(self, policy: str, config: str, setting: str) -> Path:
        return self.root / "checkpoints" / f"{policy}_{config}" / setting

    def rollout_path(self, policy: str, setting: str, channel: str) -> Path:
        return self.root / "evaluation" / "rollouts" / policy / setting / f"{channel}.parquet"

    def evaluation_table_path(self) -> Path:
        return self.root / "evaluation" / "evaluation_table.parquet"

    @staticmethod
    def describe(paths: list[Path]) -> dict:
        """Paths and content hashes for asset metadata."""
        return {p.name: {"path": str(p), "sha256": file_sha256(p), "bytes": p.stat().st_size} for p in paths}
