"""Parametrises the embodiment tests over every file in sim/catalog/embodiments."""

from __future__ import annotations

import pytest
from embodiment_scenes import robot_scene

from sim.embodiment import embodiment_names


def pytest_generate_tests(metafunc):
    if "embodiment" in metafunc.fixturenames:
        metafunc.parametrize("embodiment", embodiment_names())


@pytest.fixture
def scene(embodiment):
    return robot_scene(embodiment)
