"""Sensor-profile fields of the labels: label modalities and the occupancy block."""

import pytest

from sim.errors import SpecError
from sim.labels.grid import grid_shape
from sim.registry import DEFAULT_OCCUPANCY_BOUNDS_M, DEFAULT_OCCUPANCY_VOXEL_M, parse_sensor_profile, sensor_profile


def _raw(**changes):
    raw = dict(sensor_profile("preview").raw)
    raw.pop("occupancy", None)
    return {**raw, **changes}


def test_a_profile_without_an_occupancy_block_loads_with_the_defaults():
    profile = parse_sensor_profile(_raw(), "old.yaml")
    assert profile.occupancy_bounds_m == DEFAULT_OCCUPANCY_BOUNDS_M
    assert profile.occupancy_voxel_size_m == DEFAULT_OCCUPANCY_VOXEL_M
    assert grid_shape(profile.occupancy_bounds_m, profile.occupancy_voxel_size_m) == (60, 40, 30)


def test_catalog_profiles_declare_their_grids():
    assert grid_shape(sensor_profile("paper").occupancy_bounds_m, sensor_profile("paper").occupancy_voxel_size_m) \
        == (120, 80, 60)
    assert sensor_profile("preview").occupancy_voxel_size_m == 0.04


def test_label_modalities_are_accepted_and_unknown_ones_named():
    cams = _raw()["cameras"]
    profile = parse_sensor_profile(_raw(cameras={**cams, "modalities": ["rgb", "segmentation", "box2d", "box3d",
                                                                        "occupancy"]}))
    assert "occupancy" in profile.modalities
    with pytest.raises(SpecError, match=r"bad.yaml: field 'cameras.modalities\[1\]'.*'boxes'"):
        parse_sensor_profile(_raw(cameras={**cams, "modalities": ["rgb", "boxes"]}), "bad.yaml")


@pytest.mark.parametrize("block,field,text", [
    ({"bounds_m": [[0, 0, 0], [1, 1]]}, "occupancy.bounds_m", "[[x0, y0, z0], [x1, y1, z1]]"),
    ({"bounds_m": [[0, 0, 1], [1, 1, 0]]}, "occupancy", "x0 < x1"),
    ({"voxel_size_m": 0.03}, "occupancy", "whole number of 0.03 m voxels"),
    ({"voxel_size_m": -0.01}, "occupancy.voxel_size_m", "positive length"),
    ({"voxel_size_m": "1cm"}, "occupancy.voxel_size_m", "positive length"),
    ({"voxel": 0.01}, "occupancy.voxel", "a key from ['bounds_m', 'voxel_size_m'] (unknown key 'voxel')"),
])
def test_bad_occupancy_blocks_name_the_file_and_field(block, field, text):
    with pytest.raises(SpecError) as err:
        parse_sensor_profile(_raw(occupancy=block), "bad.yaml")
    assert err.value.path == "bad.yaml" and err.value.field == field
    assert text in str(err.value)
