"""A renderer's set-up. One made without shadows gets no shadow map (MuJoCo would allocate a 4096-square one for every
GL context, most of a context's set-up): it leaves the model as it was and refuses a later request for
shadows; one made with shadows renders them as mujoco.Renderer does. That images without shadows do not
change is shown byte for byte against mujoco.Renderer (which has the map) by test_render_speed_paths.
Its scene holds as many visual geoms as the model can draw, and a scene that fills up fails loudly."""

import mujoco
import numpy as np
import pytest

from sim.offscreen import OffscreenRenderer
from sim.scene.builder import demonstration_scene
from teleop.recorder import home

WIDTH, HEIGHT = 64, 48
CAMERA = "overhead"


@pytest.fixture(scope="module")
def scene_data():
    scene = demonstration_scene("citrus_plate_loading", "ur5_rh5dg2")
    scene.model.vis.quality.offsamples = 0      # as the camera rig without antialiasing
    scene.model.light_castshadow[:] = True      # b2d's scene light casts none (sim.scene.builder)
    return scene.model, home(scene)


def _rgb(model, data, shadows: bool) -> np.ndarray:
    renderer = OffscreenRenderer(model, WIDTH, HEIGHT, shadows=shadows)
    try:
        renderer.update(data, model.camera(CAMERA).id)
        return renderer.color().copy()
    finally:
        renderer.close()


def test_no_shadow_map_unless_asked(scene_data):
    model, data = scene_data
    size = int(model.vis.quality.shadowsize)
    renderer = OffscreenRenderer(model, WIDTH, HEIGHT)
    try:
        assert int(model.vis.quality.shadowsize) == size > 0
        with pytest.raises(ValueError, match="shadow map"):
            renderer.update(data, model.camera(CAMERA).id, shadows=True)
        renderer.update(data, model.camera(CAMERA).id, shadows=False)
        assert renderer.color().any()
    finally:
        renderer.close()


def test_shadows_when_asked_are_mujoco_renderers(scene_data):
    model, data = scene_data
    with mujoco.Renderer(model, height=HEIGHT, width=WIDTH) as reference:
        reference.update_scene(data, camera=CAMERA)
        reference.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = True
        reference.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = True
        expected = reference.render()
    with_shadows = _rgb(model, data, shadows=True)
    assert np.array_equal(with_shadows, expected)
    assert not np.array_equal(with_shadows, _rgb(model, data, shadows=False)), "no shadow was drawn"


def test_scene_capacity_covers_the_model_and_a_full_scene_fails_loudly(scene_data, tmp_path, monkeypatch):
    model, data = scene_data
    monkeypatch.chdir(tmp_path)     # MuJoCo logs its own warning to MUJOCO_LOG.TXT in the working directory
    renderer = OffscreenRenderer(model, WIDTH, HEIGHT)
    try:
        assert renderer.scene.maxgeom >= 4 * model.ngeom
        renderer.update(data, model.camera(CAMERA).id)
        assert renderer.scene.ngeom == model.ngeom       # every geom placed, none dropped
    finally:
        renderer.close()
    small = OffscreenRenderer(model, WIDTH, HEIGHT, max_geom=model.ngeom - 1)
    try:
        with pytest.raises(RuntimeError, match="visual geoms are all used"):
            small.update(data, model.camera(CAMERA).id)
    finally:
        small.close()
