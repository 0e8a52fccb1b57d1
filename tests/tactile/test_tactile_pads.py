import numpy as np
import pytest

from tactile.errors import TactileSpecError
from tactile.pads import build_pad_mesh, parse_pad

from tactile_fixtures import ROUND_PAD


def test_parse_pad_normalises_and_keeps_values(round_pad):
    assert round_pad.length == 0.03 and round_pad.curvature_radius == 0.009
    frame = round_pad.frame()
    assert np.allclose(frame.T @ frame, np.eye(3)) and np.isclose(np.linalg.det(frame), 1.0)
    assert np.allclose(frame[:, 2], [0, 1, 0]) and np.allclose(frame[:, 1], [0, 0, 1])


@pytest.mark.parametrize(
    "change, field, expected",
    [
        ({"normal": None}, "pad.normal", "missing"),
        ({"normal": [0, 2, 0]}, "pad.normal", "unit vector"),
        ({"axis": [0, 1, 0]}, "pad.axis", "orthogonal"),
        ({"width": -0.01}, "pad.width", "positive"),
        ({"center": [0, 1]}, "pad.center", "a list of 3 items"),
        ({"curvature_radius": -1}, "pad.curvature_radius", ">= 0"),
        ({"colour": "red"}, "pad.colour", "a pad key from"),
    ],
)
def test_pad_errors_name_file_field_and_expectation(change, field, expected):
    raw = dict(ROUND_PAD)
    for key, value in change.items():
        if value is None:
            raw.pop(key)
        else:
            raw[key] = value
    with pytest.raises(TactileSpecError) as err:
        parse_pad(raw, "hands/demo.yaml")
    text = str(err.value)
    assert "hands/demo.yaml" in text and f"'{field}'" in text and expected in text


def test_flat_pad_mesh_is_the_rectangle(flat_pad):
    mesh = build_pad_mesh(flat_pad)
    assert len(mesh.faces) == 2
    assert mesh.area == pytest.approx(0.02 * 0.02)
    assert np.allclose(mesh.face_normals, [0, 0, 1])


def test_rounded_pad_mesh_lies_on_its_cylinder(round_pad):
    mesh = build_pad_mesh(round_pad)
    v = mesh.vertices
    axis_point = np.array([0, 0.008 - 0.009])  # (x, y) of the cylinder axis, which runs along z
    radius = np.hypot(v[:, 0] - axis_point[0], v[:, 1] - axis_point[1])
    assert np.allclose(radius, 0.009, atol=1e-9)
    assert v[:, 2].min() == pytest.approx(0.005) and v[:, 2].max() == pytest.approx(0.035)
    outward = np.c_[mesh.triangles_center[:, :2] - axis_point, np.zeros(len(mesh.faces))]
    assert np.all(np.einsum("ij,ij->i", mesh.face_normals, outward) > 0)
    assert mesh.area == pytest.approx(np.pi * 0.009 * 0.03, rel=1e-4)  # half cylinder


def test_partly_rounded_pad_has_a_flat_middle():
    pad = parse_pad(dict(ROUND_PAD, curvature_radius=0.004), "x.yaml")
    x = np.linspace(-0.009, 0.009, 19)
    h = pad.profile(x)
    assert np.all(h[np.abs(x) <= 0.005] == 0)
    assert h[0] == pytest.approx(-0.004) and h[-1] == pytest.approx(-0.004)
