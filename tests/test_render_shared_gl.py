"""The renderers of a thread share one GL context (sim.offscreen): two renderers of different scenes and
sizes, used in turn, each give mujoco.Renderer's bytes; another thread gets a context of its own."""

import threading

import numpy as np
import pytest

from sim.offscreen import OffscreenRenderer
from sim.scene.builder import demonstration_scene
from teleop.recorder import home

from render_reference import mujoco_renderer_images

CASES = [("citrus_plate_loading", "ur5_rh5dg2", "chest", (64, 48)),
         ("fruit_bowl_loading", "ur5_rh56dfx", "overhead", (40, 30))]


@pytest.fixture(scope="module")
def scenes():
    out = []
    for task, embodiment, camera, size in CASES:
        scene = demonstration_scene(task, embodiment)
        scene.model.vis.quality.offsamples = 0
        out.append((scene.model, home(scene), camera, size))
    return out


def _images(renderer, model, data, camera):
    renderer.update(data, model.camera(camera).id)
    depth, ids = renderer.depth_and_geoms(True)
    return renderer.color().copy(), depth.copy(), ids.copy()


def test_renderers_used_in_turn_give_mujoco_renderers_bytes(scenes):
    renderers = [OffscreenRenderer(model, *size) for model, _, _, size in scenes]
    try:
        assert renderers[0]._gl is renderers[1]._gl
        expected = [mujoco_renderer_images(model, data, camera, *size) for model, data, camera, size in scenes]
        for _ in range(2):      # each renderer after the other has bound its own framebuffer
            for renderer, (model, data, camera, _), want in zip(renderers, scenes, expected):
                rgb, depth, ids = _images(renderer, model, data, camera)
                assert np.array_equal(rgb, want[0])
                assert np.array_equal(depth, want[1])
                assert np.array_equal(ids, want[2])
    finally:
        for renderer in renderers:
            renderer.close()


def test_another_thread_renders_in_a_context_of_its_own(scenes):
    model, data, camera, size = scenes[0]
    here = OffscreenRenderer(model, *size)
    got = {}

    def render_there():
        there = OffscreenRenderer(model, *size)
        try:
            got["shared"] = there._gl is here._gl
            got["rgb"] = _images(there, model, data, camera)[0]
        finally:
            there.close()

    try:
        worker = threading.Thread(target=render_there)
        worker.start()
        worker.join()
        assert got["shared"] is False
        assert np.array_equal(got["rgb"], _images(here, model, data, camera)[0])
    finally:
        here.close()


def test_a_renderer_collected_on_another_thread_is_left_with_a_warning(scenes, caplog):
    model, data, camera, size = scenes[0]
    renderer = OffscreenRenderer(model, *size)
    worker = threading.Thread(target=renderer.close)
    worker.start()
    worker.join()
    assert "another thread" in caplog.text
    assert _images(OffscreenRenderer(model, *size), model, data, camera)[0].any()   # this thread still renders
