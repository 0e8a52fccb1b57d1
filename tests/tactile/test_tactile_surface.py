import numpy as np
import pytest

from tactile.errors import TactileSpecError
from sim.embodiment.mirror import M
from tactile.surface import (
    SurfaceMap,
    load_surface_map,
    reflected_surface_map,
    save_surface_map,
    surface_map_from_pad,
    surface_map_paths,
)
from tactile_fixtures import SHARPA_DIR


def test_flat_surface_grid_units_and_normals(flat_surface):
    s = flat_surface
    assert s.point_mm.shape == (48, 48, 3) and s.normal.shape == (48, 48, 3)
    assert s.point_mm.dtype == np.float32 and s.normal.dtype == np.float32
    v = s.valid
    assert np.all(s.point_mm[v][:, 2] == 0)  # on the pad plane z = 0
    assert np.abs(s.point_mm[v][:, :2]).max() <= 10.0  # millimetres: a 20 mm pad
    assert np.abs(s.point_mm[v][:, :2]).max() > 9.5
    assert np.allclose(s.normal[v], [0, 0, -1])  # inward: into the finger
    assert not np.any(s.point_mm[~v]) and not np.any(s.normal[~v])  # empty cells are zero


def test_valid_region_matches_pad_area(round_pad):
    s = surface_map_from_pad(round_pad, resolution=120, group="R4F")
    side_mm = 30 * 1.08  # grid window: the longer side plus a 4 % margin each way
    area = s.valid.sum() * (side_mm / 120) ** 2
    assert area == pytest.approx(30 * 18, rel=0.03)
    rows, cols = np.nonzero(s.valid)
    assert rows.min() > 0 and rows.max() < 119 and cols.min() > 0 and cols.max() < 119


def test_rounded_surface_points_and_normals_are_exact(round_pad):
    s = surface_map_from_pad(round_pad, resolution=96)
    p, n = s.point_mm[s.valid].astype(np.float64), s.normal[s.valid].astype(np.float64)
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-6)
    axis_xy = np.array([0.0, -1.0])  # cylinder axis (mm): centre 8 mm minus radius 9 mm, along z
    radial = p[:, :2] - axis_xy
    radius = np.linalg.norm(radial, axis=1)
    assert np.abs(radius - 9.0).max() < 1e-3  # within 1 um of the true surface
    assert np.abs(n[:, :2] + radial / radius[:, None]).max() < 1e-3  # inward = towards the axis
    assert np.abs(n[:, 2]).max() < 1e-6
    assert 5.0 < p[:, 2].min() and p[:, 2].max() < 35.0


def test_subsample_steps(flat_surface, round_pad):
    native = surface_map_from_pad(round_pad, resolution=240)
    assert native.shape == (240, 240)
    assert native.subsample(8).shape == (30, 30) and native.subsample(7).shape == (35, 35)
    assert np.array_equal(flat_surface.subsample(4).point_mm, flat_surface.point_mm[::4, ::4])
    with pytest.raises(ValueError, match="step"):
        flat_surface.subsample(0)


def test_reflection_by_the_embodiment_mirror(round_pad):
    right = surface_map_from_pad(round_pad, resolution=24, group="R4F")
    left = reflected_surface_map(right, M, "L4F")
    assert left.group == "L4F" and left.point_mm.dtype == np.float32
    assert np.array_equal(left.point_mm[..., 0], -right.point_mm[..., 0] + 0)  # x negated, no -0.0
    assert np.array_equal(left.point_mm[..., 1:], right.point_mm[..., 1:])
    assert np.array_equal(left.normal[..., 0], -right.normal[..., 0] + 0)
    assert not np.signbit(left.point_mm[~left.valid]).any()
    with pytest.raises(ValueError, match="orthogonal"):
        reflected_surface_map(right, np.diag([2.0, 1.0, 1.0]), "L4F")


def test_save_and_load_roundtrip(tmp_path, flat_surface):
    point_path, normal_path = save_surface_map(flat_surface, tmp_path)
    assert (point_path, normal_path) == surface_map_paths(tmp_path, "FLAT")
    assert point_path.name == "FLAT_point.npy" and normal_path.name == "FLAT_normal.npy"
    loaded = load_surface_map(point_path, normal_path, "inward")
    assert loaded.group == "FLAT"
    assert np.array_equal(loaded.point_mm, flat_surface.point_mm)
    assert np.array_equal(loaded.normal, flat_surface.normal)
    flipped = load_surface_map(point_path, normal_path, "outward")
    assert np.array_equal(flipped.normal, -flat_surface.normal + 0.0)


def test_load_errors_name_file_and_field(tmp_path, flat_surface):
    point_path, normal_path = save_surface_map(flat_surface, tmp_path)
    bad = tmp_path / "BAD_normal.npy"
    np.save(bad, np.zeros((48, 48), np.float32))
    with pytest.raises(TactileSpecError, match=r"BAD_normal\.npy: field 'normal': expected an array of shape \(H, W, 3\)"):
        load_surface_map(point_path, bad, "inward")
    np.save(bad, np.zeros((24, 24, 3), np.float32))
    with pytest.raises(TactileSpecError, match=r"field 'normal': expected the point map's shape"):
        load_surface_map(point_path, bad, "inward")
    np.save(bad, flat_surface.normal * 2)
    with pytest.raises(TactileSpecError, match="unit normals"):
        load_surface_map(point_path, bad, "inward")
    with pytest.raises(TactileSpecError, match="normal_convention"):
        load_surface_map(point_path, normal_path, "sideways")
    with pytest.raises(TactileSpecError, match="existing .npy file"):
        load_surface_map(tmp_path / "missing_point.npy", normal_path, "inward")
    bad.write_bytes(b"")
    with pytest.raises(TactileSpecError, match=r"BAD_normal\.npy: field 'normal': expected a readable \.npy"):
        load_surface_map(point_path, bad, "inward")
    np.save(bad, np.array([object()] * 3, dtype=object), allow_pickle=True)
    with pytest.raises(TactileSpecError, match=r"field 'normal': expected a readable \.npy array \(no pickles\)"):
        load_surface_map(point_path, bad, "inward")


def test_save_leaves_no_temporary_files(tmp_path, flat_surface):
    save_surface_map(flat_surface, tmp_path)
    save_surface_map(flat_surface, tmp_path)     # replaces the first pair
    assert sorted(p.name for p in tmp_path.iterdir()) == ["FLAT_normal.npy", "FLAT_point.npy"]


def sharpa(group):
    point = SHARPA_DIR / f"tactileSensor_map_{group}_point.npy"
    normal = SHARPA_DIR / f"tactileSensor_map_{group}_normal.npy"
    if not (point.is_file() and normal.is_file()):
        pytest.skip(f"released Sharpa TacMap assets not found in {SHARPA_DIR}")
    return load_surface_map(point, normal, "outward", group=group)


@pytest.mark.parametrize("group, cells", [("4F", 38_000), ("TH", 45_000)])
def test_released_sharpa_assets_load_as_inward_surface_maps(group, cells):
    s = sharpa(group)
    assert isinstance(s, SurfaceMap) and s.shape == (240, 240)
    v = s.valid
    assert abs(int(v.sum()) - cells) < 0.03 * cells
    assert np.allclose(np.linalg.norm(s.normal[v], axis=1), 1.0, atol=1e-3)
    p = s.point_mm[v]
    assert 10 < np.ptp(p, axis=0).max() < 30  # a fingertip, in millimetres
    # After the flip the normals point into the fingertip (towards the shell's centre).
    towards_centre = np.einsum("ij,ij->i", s.normal[v], p.mean(axis=0) - p)
    assert np.mean(towards_centre > 0) > 0.95
