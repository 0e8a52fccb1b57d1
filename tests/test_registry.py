import pytest

from sim import registry
from sim.errors import UnknownNameError


@pytest.mark.parametrize("kind,name", [("task", "no_such_task"), ("embodiment", "ur5_robotiq"),
                                       ("channel", "full"), ("profile", "huge")])
def test_unknown_names_fail_with_the_valid_ones(kind, name):
    with pytest.raises(UnknownNameError) as err:
        registry.validate_name(kind, name)
    assert name in str(err.value) and "valid" in str(err.value)
    assert err.value.valid    # the list of valid names is carried along


def test_profiles_follow_the_paper_and_preview_is_small():
    paper, preview = registry.sensor_profile("paper"), registry.sensor_profile("preview")
    assert (paper.width, paper.height, paper.rate_hz, paper.tactile_shape) == (640, 480, 20, (240, 240))
    assert paper.camera_ids == ("chest", "overhead", "stereo_left", "stereo_right", "left_wrist", "right_wrist")
    assert preview.width * preview.height < paper.width * paper.height
    assert paper.content_hash != preview.content_hash


def test_profile_hash_tracks_content():
    raw = dict(registry.sensor_profile("preview").raw)
    changed = registry.parse_sensor_profile({**raw, "cameras": {**raw["cameras"], "width": 64}})
    assert changed.content_hash != registry.sensor_profile("preview").content_hash


def test_channels_and_paper_settings():
    assert registry.channel_names() == ["none", "equi_only", "inv_only", "inv_equi"]
    assert not registry.channel("inv_equi").anchored and registry.channel("equi_only").resample_equivariance
    settings = registry.paper_settings()
    assert len(settings) == 26
    assert registry.parse_setting_key("citrus_plate_loading__ur5_rh5dg2").available
    with pytest.raises(UnknownNameError):
        registry.parse_setting_key("citrus_plate_loading__nope")


def test_a_profile_tessellation_is_two_small_integers_named_on_error():
    import pytest

    from sim.errors import SpecError
    from sim.registry import parse_sensor_profile, sensor_profile

    assert sensor_profile("policy_tiny").tessellation == sensor_profile("preview").tessellation == (8, 4)
    assert sensor_profile("paper").tessellation == (16, 8) and sensor_profile("policy_paper").tessellation is None
    base = {"name": "t", "rate_hz": 20, "cameras": {"ids": ["chest"], "width": 8, "height": 6}}
    for bad in ([8], [8, 2], [8.0, 4], "8x4", [True, 4]):
        with pytest.raises(SpecError, match="cameras.tessellation"):
            parse_sensor_profile({**base, "cameras": {**base["cameras"], "tessellation": bad}})
