"""The rig on compiled robots: one asset per group, mirrored sides, and surfaces on the pad geoms."""

import mujoco
import numpy as np
import pytest

from sim.embodiment import add_bimanual_robot, embodiment_names
from sim.embodiment.mirror import M
from tactile.rig import TactileRig

RESOLUTION = 48  # coarse grids keep the 12 embodiments cheap; the geometry checks hold at any size
SLAB_HALF = np.array([0.02, 0.02, 0.004])  # a flat plate, 40 x 40 x 8 mm


def robot_with_slab(embodiment: str):
    """The bimanual robot plus one free flat plate far from it (the only ray target)."""
    spec = mujoco.MjSpec()
    robot = add_bimanual_robot(spec, embodiment)
    slab = spec.worldbody.add_body(name="slab", pos=[0, 0, -1])
    slab.add_freejoint(name="slab_free")
    slab.add_geom(name="slab", type=mujoco.mjtGeom.mjGEOM_BOX, size=SLAB_HALF.tolist())
    model = spec.compile()
    data = mujoco.MjData(model)
    robot.apply_home(model, data)
    return model, data, robot


@pytest.fixture(scope="module", params=embodiment_names())
def rig(request):
    model, data, robot = robot_with_slab(request.param)
    return TactileRig(model, robot, ["slab"], RESOLUTION, 1, 0.015), model, data


def test_sites_of_a_group_share_one_asset_and_sides_follow_the_policy(rig):
    rig, _, _ = rig
    by_asset = {}
    for site in rig.sites:
        by_asset.setdefault(site.asset, []).append(site)
    for asset, sites in by_asset.items():
        assert len({id(s.surface) for s in sites}) == 1, asset  # (a) one map object per asset
        assert len({s.group for s in sites}) == 1 and sites[0].surface.group == asset
    right = {s.group: s.surface for s in rig.sites if s.side == "right"}
    left = {s.group: s.surface for s in rig.sites if s.side == "left"}
    for group, surface in right.items():
        if rig.grouping == "side_shared":  # one asset for both hands: the very same arrays
            assert left[group] is surface
        else:  # (b) side-specific: the left asset differs, as the right one reflected by the mirror
            assert not np.array_equal(left[group].point_mm, surface.point_mm)
            assert np.array_equal(left[group].point_mm, (surface.point_mm @ M.T.astype(np.float32)) + 0)
            assert np.array_equal(left[group].normal, (surface.normal @ M.T.astype(np.float32)) + 0)
    described = rig.describe()
    assert described["grouping"] == rig.grouping
    assert [s["asset"] for s in described["sites"]] == [s.asset for s in rig.sites]


def _pad_geom_face(model, data, site: str):
    """World centre, outward normal, in-plane axes and half sizes of the pad geom's outer face."""
    geom = model.geom(f"{site}_pad").id
    rot = data.geom_xmat[geom].reshape(3, 3)  # builder: x along the finger, z out of the pad
    half = model.geom_size[geom]
    return data.geom_xpos[geom] + rot[:, 2] * half[2], rot[:, 2], rot[:, 0], rot[:, 1], half


def test_every_surface_lies_on_and_covers_its_pad_geoms_contact_face(rig):
    rig, model, data = rig
    for site in rig.sites:
        surface, body = site.surface, model.body(site.attach_body).id
        points = surface.point_mm[surface.valid].astype(np.float64) * 1e-3
        rot, pos = data.xmat[body].reshape(3, 3), data.xpos[body]
        world = points @ rot.T + pos
        normals = surface.normal[surface.valid].astype(np.float64) @ rot.T
        centre, out, along, across, half = _pad_geom_face(model, data, site.name)
        assert np.abs((world - centre) @ out).max() < 1e-6, site.name  # on the face, both sides
        assert np.allclose(normals, -out, atol=1e-6), site.name  # inward = into the pad
        u, v = (world - centre) @ along, (world - centre) @ across
        assert np.abs(u).max() <= half[0] + 1e-9 and np.abs(v).max() <= half[1] + 1e-9
        # the grid reaches each edge of the face to within one cell
        cell = 2 * max(half[0], half[1]) * 1.08 / RESOLUTION
        assert half[0] - np.abs(u).max() < cell and half[1] - np.abs(v).max() < cell, site.name


def press_slab(model, data, site: str, depth_m: float, edge_strip_m: float):
    """Lay the slab flat on the pad geom's face, ``depth_m`` into it, over the outer ``edge_strip_m`` of
    the face along its width (the rest of the slab hangs past the pad's edge)."""
    centre, out, along, across, half = _pad_geom_face(model, data, site)
    slab_centre = centre + out * (SLAB_HALF[2] - depth_m) + across * (half[1] - edge_strip_m + SLAB_HALF[1])
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.column_stack([along, across, out]).reshape(-1))
    adr = model.joint("slab_free").qposadr[0]
    data.qpos[adr:adr + 7] = [*slab_centre, *quat]
    mujoco.mj_forward(model, data)
    return centre, across, half


@pytest.mark.parametrize("embodiment", ["iiwa7_sharpa", "ur5_rh5dg2", "xarm7_leap"])
@pytest.mark.parametrize("side", ["right", "left"])
def test_plane_pressed_on_the_thumb_pad_edge_registers_contact(embodiment, side):
    """MuJoCo's pad geom is what touches objects, so contact at its edge must show on the tacmap.
    (A rounded tactile sheet under the flat geom lies 3.6 - 5.3 mm below it there and saw nothing.)"""
    model, data, robot = robot_with_slab(embodiment)
    rig = TactileRig(model, robot, ["slab"], 240, 2, 0.015)
    site = f"{side}_thumb_tip"
    depth, strip = 0.0005, 0.002
    centre, across, half = press_slab(model, data, site, depth, strip)
    pad, slab = model.geom(f"{site}_pad").id, model.geom("slab").id
    touching = {(c.geom1, c.geom2) for c in data.contact[: data.ncon]}
    assert (pad, slab) in touching or (slab, pad) in touching  # physics: the slab touches the pad
    frame = rig.capture(data)
    s = frame.site_names.index(site)
    assert [n for n, m in zip(frame.site_names, frame.mask) if m.any()] == [site]
    surface = rig.sites[s].surface.subsample(rig.step)
    body = model.body(rig.sites[s].attach_body).id
    world = surface.point_mm.astype(np.float64) * 1e-3 @ data.xmat[body].reshape(3, 3).T + data.xpos[body]
    v = (world - centre) @ across  # across the pad's width; the face ends at +half[1]
    in_strip = surface.valid & (v > half[1] - strip + 1e-4)
    assert in_strip.sum() >= 10 and frame.mask[s][in_strip].all()
    assert not frame.mask[s][surface.valid & (v < half[1] - strip - 1e-4)].any()
    assert np.allclose(frame.distance_m[s][in_strip], depth, atol=1e-6)
    assert frame.tacmap[s][in_strip].max() > 0
