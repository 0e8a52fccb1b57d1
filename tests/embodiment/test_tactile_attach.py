"""An embodiment file can move a tactile site to another link of its hand (the tactile registry's
site-body attachment override); bad overrides fail naming the file and field."""

import mujoco
import pytest
import yaml

from sim.embodiment import add_bimanual_robot, catalog_paths, description


@pytest.fixture
def embodiments_dir(tmp_path, monkeypatch):
    monkeypatch.setattr(catalog_paths, "EMBODIMENTS_DIR", tmp_path)     # the loaders read the folder from there
    description.load_embodiment.cache_clear()
    yield tmp_path
    description.load_embodiment.cache_clear()


def _write(folder, overrides, name="ur5_rh5dg2"):
    raw = yaml.safe_load((description.CATALOG_DIR / "embodiments" / f"{name}.yaml").read_text())
    raw["tactile_attach"] = overrides
    (folder / f"{name}.yaml").write_text(yaml.safe_dump(raw))


def _site_body(layout_model, site):
    return layout_model.body(layout_model.site_bodyid[layout_model.site(site).id]).name


def _build(folder, overrides):
    _write(folder, overrides)
    description.load_embodiment.cache_clear()
    spec = mujoco.MjSpec()
    layout = add_bimanual_robot(spec, "ur5_rh5dg2")
    return layout, spec.compile()


def test_a_site_moves_to_the_named_link_on_both_sides(embodiments_dir):
    _, base = _build(embodiments_dir, {})
    layout, model = _build(embodiments_dir, {"index_tip": "index_proximal"})
    for side in ("left", "right"):
        assert _site_body(base, f"{side}_index_tip").endswith("index_intermediate")      # the hand file's body
        assert _site_body(model, f"{side}_index_tip").endswith("index_proximal")
        assert layout.sides[side].tactile_bodies[f"{side}_index_tip"].endswith("index_proximal")
        assert _site_body(model, f"{side}_middle_tip") == _site_body(base, f"{side}_middle_tip")   # others stay


@pytest.mark.parametrize("overrides,field", [
    ({"thumb_nail": "index_proximal"}, "tactile_attach.thumb_nail"),
    ({"index_tip": "elbow"}, "tactile_attach.index_tip"),
    (["index_tip"], "tactile_attach"),
])
def test_bad_overrides_name_the_file_and_field(embodiments_dir, overrides, field):
    _write(embodiments_dir, overrides)
    with pytest.raises(description.DescriptionError, match=rf"ur5_rh5dg2.yaml: field '{field}'"):
        description.load_embodiment("ur5_rh5dg2")


def test_an_override_must_name_a_link_the_real_hand_model_maps_too(embodiments_dir):
    _write(embodiments_dir, {"index_tip": "ffmiddle"}, name="ur5_shadow")     # not in shadow's real_model.bodies
    with pytest.raises(description.DescriptionError, match=r"field 'tactile_attach.index_tip': .*real_model.bodies"):
        description.load_embodiment("ur5_shadow")
    _write(embodiments_dir, {"index_tip": "ffproximal"}, name="ur5_shadow")
    assert description.load_embodiment("ur5_shadow").tactile_attach == {"index_tip": "ffproximal"}
