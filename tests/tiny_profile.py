"""The tests' small sensor profile: every control step rendered (60 Hz), so the 18-step recordings of
tests/conftest.py give 18 frames, enough for two render workers (8 frames each at least); two 32x24
cameras and coarse tactile."""

TINY = {"name": "tiny", "rate_hz": 60,
        "cameras": {"ids": ["chest", "right_wrist"], "width": 32, "height": 24, "modalities": ["rgb", "depth"]},
        "tactile": {"enabled": True, "resolution": 240, "step": 24}}
