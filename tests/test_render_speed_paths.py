"""The render fast paths (sim.offscreen: geoms outside the view frustum skipped, a colour pass after the
id pass drawing only the geoms that own a pixel) give the same bytes as mujoco.Renderer, which draws
every geom; and a renderer collected without close() leaves other renderers' images intact (issue 23)."""

import gc

import mujoco
import numpy as np
import pytest

from sim.offscreen import OffscreenRenderer
from sim.registry import parse_sensor_profile
from sim.render import CameraRig, set_positions
from sim.scene.builder import demonstration_scene
from teleop.recorder import home

from render_reference import count_render_calls, mujoco_renderer_images

CAMERAS = ["chest", "overhead", "stereo_left", "stereo_right", "left_wrist", "right_wrist"]


def _profile(width, height, modalities=("rgb", "depth"), cameras=CAMERAS):
    return parse_sensor_profile({"name": "speed_paths", "rate_hz": 10,
                                 "cameras": {"ids": list(cameras), "width": width, "height": height,
                                             "modalities": list(modalities)}})


@pytest.fixture(scope="module")
def scene_states():
    """The foundation scene at home and at three arm poses around it (hands over the table, arms
    across each other's views)."""
    scene = demonstration_scene("citrus_plate_loading", "ur5_rh5dg2")
    data = home(scene)
    q0 = data.qpos.copy()
    rng = np.random.default_rng(7)
    states = [q0]
    for _ in range(3):
        q = q0.copy()
        q[scene.robot_qpos_adr] += rng.normal(0.0, 0.35, len(scene.robot_qpos_adr))
        states.append(q)
    return scene, data, states


@pytest.mark.parametrize("size", [(64, 48), (128, 96)])
def test_capture_equals_mujoco_renderer_bytes(scene_states, size, monkeypatch):
    """RGB, depth and segmentation of all six cameras, four poses, two resolutions: byte for byte
    mujoco.Renderer's, while the fast paths did skip geoms."""
    scene, data, states = scene_states
    model = scene.model
    width, height = size
    rig = CameraRig(model, _profile(width, height), segments=True)
    assert rig.renderer._geoms is not None, "the geom buffer view did not match this MuJoCo: nothing is culled"
    calls = count_render_calls(monkeypatch)
    try:
        shots = []
        for q in states:
            set_positions(model, data, q)
            shots.append(rig.capture(data))
    finally:
        rig.close()
    monkeypatch.undo()
    ngeom = max(n for _, n in calls)
    assert any(seg and n < ngeom for seg, n in calls), "no id pass skipped a geom outside the view"
    assert any(not seg and n < ngeom for seg, n in calls), "no colour pass skipped a geom"
    for q, shot in zip(states, shots):
        set_positions(model, data, q)
        for cam in CAMERAS:
            rgb, depth, geom_ids = mujoco_renderer_images(model, data, cam, width, height)
            got = shot[cam]
            assert got["rgb"].dtype == np.uint8 and got["rgb"].tobytes() == rgb.tobytes(), cam
            assert got["depth_m"].dtype == np.float32 and got["depth_m"].tobytes() == depth.tobytes(), cam
            assert got["segments"].geom_ids().tobytes() == geom_ids.tobytes(), cam


def test_policy_views_equal_mujoco_renderer_bytes(scene_states):
    """The closed loop's capture (four 64x48 RGB views, no id pass: frustum culling only)."""
    scene, data, states = scene_states
    model = scene.model
    views = ["stereo_left", "stereo_right", "left_wrist", "right_wrist"]
    rig = CameraRig(model, _profile(64, 48, ("rgb",), views))
    try:
        for q in states:
            set_positions(model, data, q)
            shot = rig.capture(data)
            for cam in views:
                assert set(shot[cam]) == {"rgb"}
                reference_rgb = mujoco_renderer_images(model, data, cam, 64, 48)[0]
                assert shot[cam]["rgb"].tobytes() == reference_rgb.tobytes(), cam
    finally:
        rig.close()


def _edge_model(transparent: bool) -> mujoco.MjModel:
    """Every geom type the culling bounds (and a plane), scattered around one camera's view frustum:
    many just outside it, some poking in with a tip; optionally a translucent panel across the view."""
    rng = np.random.default_rng(3)
    kinds = ["sphere", "capsule", "ellipsoid", "cylinder", "box", "mesh"]
    geoms = []
    for i in range(60):
        kind = kinds[i % len(kinds)]
        # the camera sits at the origin looking down -z (fovy 45): put geoms near the side planes
        depth = rng.uniform(0.3, 3.0)
        edge = np.tan(np.deg2rad(22.5)) * depth
        side = rng.integers(4)
        u = rng.uniform(-1.2, 1.2) * edge
        offset = edge + rng.uniform(-0.1, 0.25)
        x, y = [(offset, u), (-offset * 4 / 3, u), (u, offset), (u, -offset)][side]
        if side < 2:
            x = x * 4 / 3 if side == 0 else x
        euler = " ".join(f"{a:.3f}" for a in rng.uniform(-3, 3, 3))
        pos = f"{x:.4f} {y:.4f} {-depth:.4f}"
        rgba = f"{rng.uniform(0.2, 1):.2f} {rng.uniform(0.2, 1):.2f} {rng.uniform(0.2, 1):.2f} 1"
        size = {"sphere": "0.08", "capsule": "0.03 0.15", "ellipsoid": "0.05 0.12 0.03",
                "cylinder": "0.04 0.12", "box": "0.1 0.02 0.06", "mesh": None}[kind]
        attrs = f'type="{kind}" pos="{pos}" euler="{euler}" rgba="{rgba}"'
        attrs += ' mesh="wedge"' if kind == "mesh" else f' size="{size}"'
        geoms.append(f"<geom {attrs}/>")
    panel = '<geom type="box" pos="0 0 -0.5" size="0.15 0.15 0.005" rgba="0.2 0.9 0.2 0.4"/>' if transparent else ""
    xml = f"""
    <mujoco>
      <visual><quality offsamples="0"/><global offwidth="160" offheight="120"/></visual>
      <asset><mesh name="wedge" vertex="0 0 0  0.2 0 0  0 0.1 0  0 0 0.15  0.2 0.1 0.05"/></asset>
      <worldbody>
        <light pos="0 0 2" dir="0 0 -1"/>
        <camera name="cam" pos="0 0 0" fovy="45"/>
        <geom type="plane" pos="0 0 -3.5" size="4 4 0.1" rgba="0.5 0.5 0.5 1"/>
        {panel}
        {''.join(geoms)}
      </worldbody>
    </mujoco>"""
    return mujoco.MjModel.from_xml_string(xml)


@pytest.mark.parametrize("transparent", [False, True])
def test_geoms_at_the_frustum_edge(transparent, monkeypatch):
    """Geoms of every culled type straddling the view's edges: the same bytes as mujoco.Renderer; some
    are skipped, so the bounds are exercised (and with a translucent geom in view the colour pass keeps
    every geom in view: the id pass does not tell what shows through it)."""
    model = _edge_model(transparent)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    width, height = 160, 120
    off = OffscreenRenderer(model, width, height)
    calls = count_render_calls(monkeypatch)
    try:
        off.update(data, 0)
        depth, geom_ids = off.depth_and_geoms(True)
        rgb = off.color()
    finally:
        off.close()
    monkeypatch.undo()
    (seg_pass, drawn_ids), (_, drawn_rgb) = calls
    assert seg_pass and drawn_ids < model.ngeom
    if transparent:
        assert drawn_rgb == drawn_ids
    else:
        assert drawn_rgb < drawn_ids
    ref_rgb, ref_depth, ref_ids = mujoco_renderer_images(model, data, "cam", width, height)
    assert len(np.unique(ref_ids)) > 10      # many geoms do show
    assert rgb.tobytes() == ref_rgb.tobytes()
    assert depth.tobytes() == ref_depth.tobytes()
    assert geom_ids.tobytes() == ref_ids.tobytes()


def _same(a: dict, b: dict) -> bool:
    return all(a[c]["rgb"].tobytes() == b[c]["rgb"].tobytes()
               and a[c]["depth_m"].tobytes() == b[c]["depth_m"].tobytes()
               and a[c]["segments"].index.tobytes() == b[c]["segments"].index.tobytes() for c in a)


def test_renderer_dropped_without_close_leaves_others_intact(scene_states):
    """Issue 23: a rig garbage-collected without close() freed its GL objects in whichever context was
    current - another renderer's, whose images then came out as noise."""
    scene, data, states = scene_states
    model = scene.model
    set_positions(model, data, states[0])
    profile = _profile(64, 48, cameras=["stereo_left", "left_wrist"])
    first = CameraRig(model, profile, segments=True)
    reference = first.capture(data)
    first.close()

    before = CameraRig(model, profile, segments=True)          # built before the dropped one
    assert _same(before.capture(data), reference)
    dropped = CameraRig(model, profile, segments=True)
    dropped.capture(data)
    before.capture(data)                                        # its context is current when the other goes
    del dropped
    gc.collect()
    assert _same(before.capture(data), reference)

    rig = None
    for _ in range(3):      # an evaluator building a rig per episode: the last one goes once the next exists
        rig = CameraRig(model, profile, segments=True)
        gc.collect()
        assert _same(rig.capture(data), reference)
    assert _same(before.capture(data), reference)
    before.close()
    rig.close()
    rig.close()                                                 # closing twice is harmless


def test_a_profile_tessellation_is_the_one_its_rig_draws_with(scene_states):
    """Issue 22: preview (like policy_tiny) draws primitives at (8, 4) slices/stacks. Rigs of one profile
    give the same bytes whatever rig of another tessellation was made on the model between them, and the
    coarse images differ from MuJoCo's default ones (the profile's hash says so)."""
    from sim.registry import sensor_profile

    scene, data, states = scene_states
    model = scene.model
    set_positions(model, data, states[1])
    cams = ["stereo_left", "left_wrist"]
    coarse_raw = {**_profile(64, 48, cameras=cams).raw}
    coarse_raw["cameras"] = {**coarse_raw["cameras"], "tessellation": [8, 4]}
    coarse = parse_sensor_profile(coarse_raw)
    default = _profile(64, 48, cameras=cams)
    assert coarse.content_hash != default.content_hash and sensor_profile("preview").tessellation == (8, 4)
    shots = []
    for profile in (coarse, default, coarse, default):
        rig = CameraRig(model, profile, segments=True)
        try:
            shots.append(rig.capture(data))
        finally:
            rig.close()
    assert _same(shots[0], shots[2]) and _same(shots[1], shots[3])
    assert not any(shots[0][c]["rgb"].tobytes() == shots[1][c]["rgb"].tobytes() for c in cams)
