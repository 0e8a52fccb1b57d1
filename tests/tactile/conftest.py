"""Fixtures for the tactile tests: small flat and rounded pads and their surface maps."""

import pytest

from tactile.pads import parse_pad
from tactile.surface import surface_map_from_pad
from tactile_fixtures import FLAT_PAD, ROUND_PAD


@pytest.fixture(scope="session")
def flat_pad():
    return parse_pad(FLAT_PAD, "flat_pad.yaml")


@pytest.fixture(scope="session")
def round_pad():
    return parse_pad(ROUND_PAD, "round_pad.yaml")


@pytest.fixture(scope="session")
def flat_surface(flat_pad):
    """20 x 20 mm flat pad in the z = 0 plane, inward normal -z, 48 x 48 cells (~0.45 mm)."""
    return surface_map_from_pad(flat_pad, resolution=48, group="FLAT")
