import numpy as np
import pytest
import trimesh
from scipy.ndimage import binary_erosion

from tactile.broadphase import LocalBox, aabb_overlaps, boxes_overlap, world_aabbs
from tactile.quantize import quantize_depth
from tactile.raycast import MeshRaycaster
from tactile.sensor import TactileSensor, TactileSite
from tactile.surface import load_surface_map
from tactile_fixtures import IDENTITY, SHARPA_DIR, rotation

BOX = trimesh.creation.box([0.05, 0.05, 0.05])  # 50 mm cube centred on its local origin
SPHERE_R = 0.01
SPHERE = trimesh.creation.icosphere(subdivisions=5, radius=SPHERE_R)
FAR = (np.array([0, 0, 1.0]), np.eye(3))


def sensor_for(surface, targets, step=1, sites=("s",)):
    sensor = TactileSensor([TactileSite(name, surface) for name in sites], step=step)
    for name, mesh in targets.items():
        sensor.add_target(name, mesh)
    return sensor


def world(site_pose, offset, rot=np.eye(3)):
    """Pose given in the site frame -> world pose."""
    pos, r = site_pose
    return r @ np.asarray(offset) + pos, r @ rot


@pytest.mark.parametrize("depth_m", [0.0003013, 0.0012, 0.006])
def test_box_pressed_into_flat_pad_gives_the_formula_everywhere(flat_surface, depth_m):
    site_pose = (np.array([0.2, -0.3, 0.8]), rotation([1, 2, 3], 0.7))  # arbitrary world pose
    sensor = sensor_for(flat_surface, {"box": BOX})
    frame = sensor.sense({"s": site_pose}, {"box": world(site_pose, [0, 0, 0.025 - depth_m], rotation([0, 0, 1], 0.3))})
    valid = flat_surface.valid
    assert np.array_equal(frame.mask[0], valid)
    assert np.allclose(frame.distance_m[0][valid], depth_m, atol=2e-8)
    assert not frame.distance_m[0][~valid].any()
    level = quantize_depth(np.array([depth_m]), np.array([True]))[0]
    interior = binary_erosion(valid, iterations=4)  # 9 x 9 kernel: 4 cells from the edge
    assert interior.sum() > 1000
    assert np.all(frame.tacmap[0][interior] == level)
    assert frame.tacmap[0].max() == level and frame.tacmap.dtype == np.uint8


def test_box_at_step_4_uses_the_subsampled_grid(round_pad):
    from tactile.surface import surface_map_from_pad

    surface = surface_map_from_pad(round_pad, resolution=240)
    sensor = sensor_for(surface, {"box": BOX}, step=4)
    # Box face 0.8 mm below the pad top (y = 8 mm), pressing along -y of the attach body.
    frame = sensor.sense({"s": IDENTITY}, {"box": (np.array([0, 0.008 + 0.025 - 0.0008, 0.02]), np.eye(3))})
    assert frame.tacmap.shape == (1, 60, 60)
    # On the rounded pad the contact is the strip where the profile is above the face: |x| < sqrt(2 R d - d^2).
    pts = surface.subsample(4).point_mm
    half_width_mm = np.sqrt(2 * 9 * 0.8 - 0.8**2)
    inside = surface.subsample(4).valid & (np.abs(pts[..., 0]) < half_width_mm - 0.2)
    outside = surface.subsample(4).valid & (np.abs(pts[..., 0]) > half_width_mm + 0.2)
    assert frame.mask[0][inside].all() and not frame.mask[0][outside].any()
    # Rays run along the inward (radial) normal, so the depth to the face y = 7.2 mm is the
    # vertical gap over the cosine of the normal's tilt: cos = (y - y_axis) / R, y_axis = -1 mm.
    expected = (pts[..., 1] - (8 - 0.8)) / ((pts[..., 1] + 1) / 9) * 1e-3
    assert np.allclose(frame.distance_m[0][inside], expected[inside], atol=1e-7)


def test_sphere_footprint_is_a_disc_of_the_expected_radius(flat_surface):
    depth = 0.001
    sensor = sensor_for(flat_surface, {"sphere": SPHERE})
    frame = sensor.sense({"s": IDENTITY}, {"sphere": (np.array([0, 0, SPHERE_R - depth]), np.eye(3))})
    radius_mm = np.sqrt(2 * SPHERE_R * depth - depth**2) * 1e3  # 4.36 mm
    r = np.where(flat_surface.valid, np.linalg.norm(flat_surface.point_mm[..., :2], axis=-1), np.inf)
    cell_mm = 20 * 1.08 / 48
    assert frame.mask[0][r < radius_mm - cell_mm].all()
    assert not frame.mask[0][r > radius_mm + cell_mm].any()
    assert frame.mask.sum() == pytest.approx(np.pi * radius_mm**2 / cell_mm**2, rel=0.1)
    inside = frame.mask[0]
    expected = np.sqrt(SPHERE_R**2 - (r[inside] * 1e-3) ** 2) - (SPHERE_R - depth)
    assert np.abs(frame.distance_m[0][inside] - expected).max() < 5e-6  # facets of the icosphere
    assert frame.distance_m[0].max() == pytest.approx(expected.max(), abs=5e-6) and expected.max() > 0.99 * depth
    centre = np.unravel_index(np.argmin(r), r.shape)
    assert frame.tacmap[0][centre] == frame.tacmap[0].max() > 100


def test_object_near_but_not_touching_gives_zeros(flat_surface):
    sensor = sensor_for(flat_surface, {"sphere": SPHERE})
    # 0.5 mm above the pad; tilted so its bounding box reaches into the pad's ray volume.
    pose = (np.array([0, 0, SPHERE_R + 0.0005]), rotation([1, 0, 0], np.pi / 4))
    assert sensor.candidate_pairs({"s": IDENTITY}, {"sphere": pose}) == [("s", "sphere")]
    frame = sensor.sense({"s": IDENTITY}, {"sphere": pose})
    assert frame.rays_cast == flat_surface.valid.sum()  # rays were cast, and none hit
    assert not frame.mask.any() and not frame.distance_m.any() and not frame.tacmap.any()


def test_reverse_pass_rejects_an_object_behind_the_pad(flat_surface):
    """Pass 1 hits a box lying 3 mm inside the finger; pass 2 (cast outward from just short of
    that hit) meets nothing, because the box never crossed the nominal surface."""
    pose = (np.array([0, 0, -0.003 - 0.025]), np.eye(3))
    valid = flat_surface.valid.reshape(-1)
    origins = flat_surface.point_mm.reshape(-1, 3)[valid] * 1e-3 - pose[0]
    directions = flat_surface.normal.reshape(-1, 3)[valid]
    first = MeshRaycaster(BOX).depth(origins, directions, 0.015)
    assert np.allclose(first, 0.003, atol=1e-7)  # pass 1 alone would report 3 mm everywhere
    frame = sensor_for(flat_surface, {"box": BOX}).sense({"s": IDENTITY}, {"box": pose})
    assert frame.rays_cast == 2 * valid.sum()  # both passes ran
    assert not frame.mask.any() and not frame.distance_m.any() and not frame.tacmap.any()


def test_beyond_range_is_a_miss(flat_surface):
    sensor = sensor_for(flat_surface, {"box": BOX})
    frame = sensor.sense({"s": IDENTITY}, {"box": (np.array([0, 0, 0.025 - 0.016]), np.eye(3))})
    # The box is pressed 16 mm deep: its far face lies beyond the 15 mm range.
    assert not frame.mask.any()


def test_nearest_target_wins_and_is_the_one_checked(flat_surface):
    sensor = sensor_for(flat_surface, {"box": BOX, "sphere": SPHERE})
    poses = {"box": (np.array([0, 0, 0.025 - 0.002]), np.eye(3)), "sphere": (np.array([0, 0, -0.004 - SPHERE_R]), np.eye(3))}
    frame = sensor.sense({"s": IDENTITY}, poses)
    # The sphere (4 mm behind the pad) is farther than the box exit (2 mm): the box decides.
    assert np.array_equal(frame.mask[0], flat_surface.valid)
    assert np.allclose(frame.distance_m[0][flat_surface.valid], 0.002, atol=2e-8)


def test_sensing_is_deterministic(flat_surface):
    poses = {"sphere": (np.array([0.001, -0.002, SPHERE_R - 0.0013]), rotation([1, 1, 0], 0.4))}
    site = {"s": (np.array([0.0, 0.0, 0.0]), rotation([0, 1, 1], 0.0))}
    a = sensor_for(flat_surface, {"sphere": SPHERE}).sense(site, poses)
    b = sensor_for(flat_surface, {"sphere": SPHERE}).sense(site, poses)
    assert a.mask.any()
    for name in ("tacmap", "distance_m", "mask"):
        assert getattr(a, name).tobytes() == getattr(b, name).tobytes()


def test_broad_phase_skips_far_sites(flat_surface):
    sensor = sensor_for(flat_surface, {"sphere": SPHERE}, sites=("near", "far", "also_far"))
    site_poses = {"near": IDENTITY, "far": FAR, "also_far": (np.array([0.05, 0, 0]), np.eye(3))}
    poses = {"sphere": (np.array([0, 0, SPHERE_R - 0.001]), np.eye(3))}
    assert sensor.candidate_pairs(site_poses, poses) == [("near", "sphere")]
    frame = sensor.sense(site_poses, poses)
    assert frame.site_names == ("near", "far", "also_far")
    assert frame.rays_cast < 2 * flat_surface.valid.sum()
    assert frame.mask[0].any() and not frame.mask[1:].any()
    with pytest.raises(KeyError, match="also_far"):
        sensor.sense({"near": IDENTITY, "far": FAR}, poses)


def test_oriented_box_overlap_uses_edge_axes():
    # Two unit cubes tilted 45 deg about x and about y, stacked on z: only the edge-edge axis
    # (z = x-edge cross y-edge) separates them once their centres are more than 2 sqrt(2) apart.
    unit = LocalBox(np.zeros(3), np.ones(3))
    a = unit.in_world(np.zeros(3), rotation([1, 0, 0], np.pi / 4))
    for gap, overlap in [(-0.01, True), (0.01, False)]:
        b = unit.in_world(np.array([0, 0, 2 * np.sqrt(2) + gap]), rotation([0, 1, 0], np.pi / 4))
        assert boxes_overlap(a, b) is overlap
    assert boxes_overlap(unit.in_world(np.zeros(3), np.eye(3)), unit.in_world(np.array([1.9, 0, 0]), np.eye(3)))
    assert not boxes_overlap(unit.in_world(np.zeros(3), np.eye(3)), unit.in_world(np.array([2.1, 0, 0]), np.eye(3)))


def test_world_aabb_prefilter_keeps_every_pair_the_exact_test_keeps():
    rng = np.random.default_rng(0)

    def random_boxes(n):
        return [LocalBox(rng.uniform(-0.02, 0.02, 3), rng.uniform(0.005, 0.03, 3)).in_world(
            rng.uniform(-0.08, 0.08, 3), rotation(rng.normal(size=3), rng.uniform(0, np.pi))) for _ in range(n)]

    sites, targets = random_boxes(40), random_boxes(60)
    near = aabb_overlaps(world_aabbs(sites), world_aabbs(targets))
    exact = np.array([[boxes_overlap(a, b) for b in targets] for a in sites])
    assert exact.any() and (near & ~exact).any()     # the sample has both kinds of pair
    assert not (exact & ~near).any()


def test_sensor_rejects_bad_setup(flat_surface, round_pad):
    from tactile.surface import surface_map_from_pad

    with pytest.raises(ValueError, match="unique"):
        TactileSensor([TactileSite("a", flat_surface), TactileSite("a", flat_surface)])
    other = surface_map_from_pad(round_pad, resolution=24)
    with pytest.raises(ValueError, match="one shape"):
        TactileSensor([TactileSite("a", flat_surface), TactileSite("b", other)])
    sensor = sensor_for(flat_surface, {"box": BOX})
    with pytest.raises(ValueError, match="already registered"):
        sensor.add_target("box", BOX)


def test_sphere_pressed_into_released_sharpa_fingertip():
    point, normal = (SHARPA_DIR / f"tactileSensor_map_4F_{k}.npy" for k in ("point", "normal"))
    if not (point.is_file() and normal.is_file()):
        pytest.skip(f"released Sharpa TacMap assets not found in {SHARPA_DIR}")
    surface = load_surface_map(point, normal, "outward", group="4F")
    sensor = sensor_for(surface, {"sphere": SPHERE}, step=4)
    p0, n0 = surface.point_mm[120, 120] * 1e-3, surface.normal[120, 120]
    depth = 0.0008
    frame = sensor.sense({"s": IDENTITY}, {"sphere": (p0 - n0 * (SPHERE_R - depth), np.eye(3))})
    assert frame.mask[0][30, 30] and frame.distance_m[0][30, 30] == pytest.approx(depth, abs=1e-5)
    assert 10 < frame.mask.sum() < surface.subsample(4).valid.sum() / 2
