import cv2
import numpy as np
import pytest

from tactile.quantize import encode_tacmap, quantize_depth, smooth_tacmap, smoothing_kernel_size


def q(depth_m, dtype=np.float32):
    return int(quantize_depth(np.array([depth_m], dtype=dtype), np.array([True]))[0])


@pytest.mark.parametrize(
    "depth_m, level",
    [
        (0.0, 0),
        (0.00025, 50),  # 0.25 mm / 0.005
        (0.0003013, 60),
        (0.00049999, 99),  # the fine branch just below 0.5 mm: 99.998 truncates to 99
        (0.0005, 100),  # both branches give 100 at 0.5 mm: q is continuous there
        (0.001, 116),  # (1.0 - 0.5) / 0.03 + 100 = 116.67 -> 116
        (0.0012, 123),
        (0.0051499, 254),
        (0.00515, 255),  # saturation starts at 5.15 mm
        (0.015, 255),
    ],
)
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_quantizer_levels(depth_m, level, dtype):
    assert q(depth_m, dtype) == level


def test_quantizer_is_continuous_at_half_millimetre():
    z = 0.5 - 1e-12
    assert z / 0.005 == pytest.approx(100.0) and (0.5 - 0.5) / 0.03 + 100 == 100.0


def test_masked_and_negative_samples_are_zero():
    depth = np.array([[0.002, 0.002], [-0.001, 0.0]], dtype=np.float32)
    mask = np.array([[True, False], [True, True]])
    assert quantize_depth(depth, mask).tolist() == [[150, 0], [0, 0]]


def test_shape_mismatch_is_an_error():
    with pytest.raises(ValueError, match="shape"):
        quantize_depth(np.zeros((4, 4), np.float32), np.zeros((4, 5), bool))


@pytest.mark.parametrize("step, size", [(1, 9), (2, 5), (3, 3), (4, 3), (5, 1), (8, 1), (9, 1), (12, 1)])
def test_kernel_size_follows_the_paper(step, size):
    assert smoothing_kernel_size(step) == size


def test_smoothing_matches_a_float_gaussian_and_rounds():
    image = np.zeros((21, 21), np.uint8)
    image[10, 10] = 255
    smoothed = smooth_tacmap(image, step=1)
    kernel = cv2.getGaussianKernel(9, 1.5).astype(np.float64)
    expected = np.zeros((21, 21))
    expected[6:15, 6:15] = 255 * kernel @ kernel.T
    assert smoothed.dtype == np.uint8
    assert np.abs(smoothed.astype(int) - np.rint(expected)).max() <= 1
    assert smoothed[10, 10] == np.rint(255 * kernel[4, 0] ** 2)


def test_constant_field_survives_smoothing_and_large_steps_skip_it():
    flat = np.full((16, 16), 123, np.uint8)
    assert np.array_equal(smooth_tacmap(flat, 1), flat)
    depth = np.random.default_rng(0).uniform(0, 0.006, (30, 30)).astype(np.float32)
    mask = depth > 0.001
    assert np.array_equal(encode_tacmap(depth, mask, step=8), quantize_depth(depth, mask))
