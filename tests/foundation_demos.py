"""Short real demonstrations of the foundation setting, for the session fixtures that need recordings."""

from pathlib import Path

SETTING = "citrus_plate_loading__ur5_rh5dg2"
TASK, EMBODIMENT = SETTING.split("__")


def record_foundation_demos(out: Path, episodes: int, max_steps: int) -> list[Path]:
    """Raw recordings of `episodes` scripted demonstrations, `max_steps` control steps each."""
    from teleop.demos import record_demonstrations

    results = record_demonstrations(TASK, EMBODIMENT, episodes, out, max_steps=max_steps)
    assert all(r.error is None for r in results), [r.error for r in results]
    return [r.path for r in results]
