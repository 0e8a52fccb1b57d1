"""A still camera's passes of the geoms welded to the world are rendered once and merged by depth with
each frame's pass of the other geoms (sim.still_layers): the same bytes as rendering every pass
whole, including on depth ties, where the geom MuJoCo draws later wins (issue 22)."""

import mujoco
import numpy as np
import pytest

import sim.offscreen
from episodes.atomic import file_sha256
from episodes.stages import render_to_file, replay_to_file
from sim.offscreen import OffscreenRenderer
from sim.registry import parse_sensor_profile
from sim.render import CameraRig, set_positions
from sim.scene.builder import demonstration_scene
from teleop.recorder import home

from render_reference import count_render_calls, mujoco_renderer_images

CAMERAS = ["chest", "overhead", "stereo_left", "stereo_right", "left_wrist", "right_wrist"]


def _profile(width, height, cameras=CAMERAS, modalities=("rgb", "depth", "segmentation"), rate_hz=10):
    return parse_sensor_profile({"name": "still_layers", "rate_hz": rate_hz,
                                 "cameras": {"ids": list(cameras), "width": width, "height": height,
                                             "modalities": list(modalities)}})


def test_foundation_cameras_same_bytes_as_whole_passes(monkeypatch):
    """Six cameras, five poses (home, then the arms moved): layered and whole renders agree byte for
    byte; the still cameras did render their frames from a kept layer, the wrist cameras did not."""
    scene = demonstration_scene("citrus_plate_loading", "ur5_rh5dg2")
    model, data = scene.model, home(scene)
    q0 = data.qpos.copy()
    rng = np.random.default_rng(11)
    states = [q0] + [q0 + np.isin(np.arange(model.nq), scene.robot_qpos_adr) * rng.normal(0, 0.3, model.nq)
                     for _ in range(4)]
    profile = _profile(96, 72)
    layered = CameraRig(model, profile, segments=True)
    whole = CameraRig(model, profile, segments=True, still_layers=False)
    still = {model.camera(i).name for i in layered.renderer._still_cameras}
    assert still == {"chest", "overhead", "stereo_left", "stereo_right"}
    try:
        for q in states:
            set_positions(model, data, q)
            a, b = layered.capture(data), whole.capture(data)
            for cam in CAMERAS:
                assert a[cam]["rgb"].tobytes() == b[cam]["rgb"].tobytes(), cam
                assert a[cam]["depth_m"].tobytes() == b[cam]["depth_m"].tobytes(), cam
                assert a[cam]["segments"].geom_ids().tobytes() == b[cam]["segments"].geom_ids().tobytes(), cam
        layers = layered.renderer._layers
        assert set(layers) == {model.camera(c).id for c in still}
        assert all(layer.ids is not None and layer.rgb is not None for layer in layers.values())
        # a layered frame draws fewer geoms than the whole pass of the same camera
        calls = count_render_calls(monkeypatch)
        set_positions(model, data, states[-1])
        layered.capture(data)
        layered_ids = [n for seg, n in calls if seg]
        calls.clear()
        whole.capture(data)
        whole_ids = [n for seg, n in calls if seg]
        assert sum(layered_ids) < sum(whole_ids)
    finally:
        layered.close()
        whole.close()


def _tie_model(welded_first: bool) -> mujoco.MjModel:
    """Two identical boxes at the same pose, one welded to the world and one on a slide joint, seen by a
    still camera: every pixel of them is a depth tie, which the geom drawn later wins. Geoms are drawn
    in id order, bodies depth first: the world body's own geom comes first; a welded child body declared
    after the moving one comes last."""
    welded_world = '<geom type="box" size="0.2 0.2 0.2" pos="0 0 0.5" rgba="1 0 0 1"/>'
    moving = """<body name="mover" pos="0 0 0.5"><joint type="slide" axis="1 0 0"/>
                  <geom type="box" size="0.2 0.2 0.2" rgba="0 0 1 1"/></body>"""
    welded_child = """<body name="fixed" pos="0 0 0.5">
                        <geom type="box" size="0.2 0.2 0.2" rgba="0 1 0 1"/></body>"""
    bodies = (welded_world + moving) if welded_first else (moving + welded_child)
    xml = f"""
    <mujoco>
      <visual><quality offsamples="0"/><global offwidth="80" offheight="60"/></visual>
      <worldbody>
        <light pos="0 0 3" dir="0 0 -1"/>
        <camera name="cam" pos="0.9 -0.9 1.4" xyaxes="1 1 0 -0.5 0.5 1"/>
        <geom type="plane" size="2 2 0.1" rgba="0.5 0.5 0.5 1"/>
        <geom type="sphere" size="0.1" pos="0.3 0.3 0.1" rgba="0.9 0.9 0.2 1"/>
        {bodies}
      </worldbody>
    </mujoco>"""
    return mujoco.MjModel.from_xml_string(xml)


@pytest.mark.parametrize("welded_first", [True, False])
def test_depth_ties_go_to_the_geom_drawn_later(welded_first):
    model = _tie_model(welded_first)
    data = mujoco.MjData(model)
    width, height = 80, 60
    off = OffscreenRenderer(model, width, height)
    try:
        for _ in range(2):     # the first placement is rendered whole, the second from the kept layer
            mujoco.mj_forward(model, data)
            off.update(data, 0)
            depth, geom_ids = off.depth_and_geoms(True)
            rgb = off.color()
        assert off._merged is not None and off._layers[0].rgb is not None, "the layer was not used"
    finally:
        off.close()
    ref_rgb, ref_depth, ref_ids = mujoco_renderer_images(model, data, "cam", width, height)
    mover = model.body("mover").id
    later = max(g for g in range(model.ngeom) if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX)
    assert (ref_ids == later).sum() > 200          # the tie is real and decided by draw order
    assert (model.geom_bodyid[later] == mover) == welded_first
    assert geom_ids.tobytes() == ref_ids.tobytes()
    assert depth.tobytes() == ref_depth.tobytes()
    assert rgb.tobytes() == ref_rgb.tobytes()


def test_render_file_is_byte_identical_with_and_without_layers(raw_path, tmp_path, monkeypatch):
    """The render stage on a real replay: the same file, byte for byte, whether still cameras keep
    layers or every pass is rendered whole."""
    replay = tmp_path / "e.replay.h5"
    replay_to_file(raw_path, replay)
    profile = _profile(48, 36, ["chest", "overhead", "right_wrist"], rate_hz=60)
    layered = render_to_file(replay, profile, tmp_path / "layered.render.h5")
    monkeypatch.setattr(sim.offscreen, "still_cameras", lambda model, welded: set())
    whole = render_to_file(replay, profile, tmp_path / "whole.render.h5")
    assert layered["frames"] == whole["frames"] >= 10
    assert file_sha256(tmp_path / "layered.render.h5") == file_sha256(tmp_path / "whole.render.h5")


def test_a_changed_welded_geom_or_light_is_rendered_anew():
    """The kept layer is keyed on the welded geoms' records, the cameras and the lights: recolouring the
    welded box or moving the light between frames gives the new image, not the kept one."""
    model = _tie_model(True)
    data = mujoco.MjData(model)
    width, height = 80, 60
    off = OffscreenRenderer(model, width, height)
    welded_box = min(g for g in range(model.ngeom) if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX)
    try:
        for change in (None, None, "colour", None, "light"):   # a layer is kept from the second sighting on
            if change == "colour":
                model.geom_rgba[welded_box] = [0.2, 0.8, 0.3, 1]
                model.geom_pos[welded_box] += [0.05, 0, 0]      # out of the tie: the welded box shows
            elif change == "light":
                model.light_pos[0] = [0.5, -0.5, 2.5]
            mujoco.mj_forward(model, data)
            off.update(data, 0)
            depth, geom_ids = off.depth_and_geoms(True)
            rgb = off.color()
            ref_rgb, ref_depth, ref_ids = mujoco_renderer_images(model, data, "cam", width, height)
            assert rgb.tobytes() == ref_rgb.tobytes(), change
            assert depth.tobytes() == ref_depth.tobytes() and geom_ids.tobytes() == ref_ids.tobytes(), change
    finally:
        off.close()
