"""Training episodes at the policy's inputs: the stored replays rendered under the policy's sensor profile
(four views at the policy's resolution and rate) and assembled into HDF5 episodes. No re-teleoperation:
the replays already hold every state."""

from __future__ import annotations

import logging
from pathlib import Path

from episodes import schema
from episodes.stages import assemble_episode, render_to_file
from sim.registry import SensorProfile

log = logging.getLogger(__name__)


def render_policy_episodes(replays: list[Path], profile: SensorProfile, out_dir: Path,
                           progress=None) -> tuple[list[Path], dict[str, str]]:
    """One episode per replay under `profile` in `out_dir`; returns (written episodes, {replay: error}).
    A bad replay is reported and skipped, never stopping the others."""
    out_dir = Path(out_dir)
    work = out_dir / ".work"
    written, errors = [], {}
    for replay in sorted(replays):
        stem = Path(replay).name.removesuffix(".replay.h5")
        render = work / f"{stem}.{profile.content_hash}.render.h5"
        out = out_dir / schema.episode_filename(stem.removeprefix("episode_"))
        try:
            render_to_file(Path(replay), profile, render)
            assemble_episode(Path(replay), render, profile, out)
            written.append(out)
        except Exception as exc:          # one bad episode never stops the others
            log.exception("rendering %s for policy inputs failed", replay)
            errors[Path(replay).name] = f"{type(exc).__name__}: {exc}"
        finally:
            render.unlink(missing_ok=True)
        if progress:
            progress(1)
    return written, errors
