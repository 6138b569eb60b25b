"""geocull.compare: pure numpy metrics, no extension needed."""

import math

import numpy as np
import pytest

from geocull.compare import coverage, coverage_agreement, depth_error, image_error


def _img(h=10, w=10, c=4, value=0):
    return np.full((h, w, c), value, dtype=np.uint8)


def test_identical_images():
    a = np.random.default_rng(0).integers(0, 256, (10, 10, 4), dtype=np.uint8)
    e = image_error(a, a.copy())
    assert e["differing_pixel_fraction"] == 0.0
    assert e["psnr"] == math.inf
    assert e["max_abs_diff"] == 0
    assert e["missing_tiles"] is None


def test_one_pixel_changed():
    a = _img()
    b = a.copy()
    b[3, 7, 1] = 200
    e = image_error(a, b)
    assert e["differing_pixel_fraction"] == pytest.approx(0.01)
    assert e["max_abs_diff"] == 200
    mse = 200.0**2 / (10 * 10 * 4)
    assert e["psnr"] == pytest.approx(10 * math.log10(255.0**2 / mse))


def test_threshold():
    a = _img()
    b = a.copy()
    b[0, 0, 0] = 5
    b[1, 1, 2] = 6
    assert image_error(a, b, threshold=5)["differing_pixel_fraction"] == pytest.approx(0.01)
    assert image_error(a, b, threshold=6)["differing_pixel_fraction"] == 0.0


def test_rgba_against_rgb_compares_rgb_only():
    a = _img(c=4, value=7)
    a[..., 3] = 255
    b = _img(c=3, value=7)
    e = image_error(a, b)
    assert e["differing_pixel_fraction"] == 0.0


def test_missing_tiles():
    a = _img()
    ref = np.array([0, 5, 12, 0, 1], dtype=np.uint32)
    drawn = np.array([False, True, False, True, False])
    assert image_error(a, a, tile_drawn=drawn, reference_tile_pixels=ref)["missing_tiles"] == 2
    assert image_error(a, a, tile_drawn=np.ones(5, bool), reference_tile_pixels=ref)["missing_tiles"] == 0


def test_missing_tiles_needs_both_arrays():
    a = _img()
    with pytest.raises(ValueError, match="reference_tile_pixels"):
        image_error(a, a, tile_drawn=np.ones(3, bool))
    with pytest.raises(ValueError, match="reference_tile_pixels"):
        image_error(a, a, tile_drawn=np.ones(3, bool), reference_tile_pixels=np.ones(4))


def test_shape_mismatch_names_b():
    with pytest.raises(ValueError, match=r"^b\b"):
        image_error(_img(10, 10), _img(10, 11))


def test_bad_dtype_and_ndim():
    with pytest.raises(ValueError, match=r"^a\b"):
        image_error(np.zeros((10, 10, 4), np.float32), _img())
    with pytest.raises(ValueError, match=r"^b\b"):
        image_error(_img(), np.zeros((10, 10), np.uint8))


def test_depth_metrics():
    a = np.array([[1.0, np.inf], [2.0, 4.0]], dtype=np.float32)
    b = np.array([[1.0, np.inf], [np.inf, 4.4]], dtype=np.float32)
    assert coverage(a).tolist() == [[True, False], [True, True]]
    assert coverage_agreement(a, b) == pytest.approx(0.75)
    e = depth_error(a, b)
    assert e["n_common"] == 2
    assert e["max_rel"] == pytest.approx(0.4 / 4.4, rel=1e-5)
    assert e["fraction_over_tol"] == pytest.approx(0.5)
    with pytest.raises(ValueError, match="depth_b"):
        coverage_agreement(a, b[:1])
    none = depth_error(np.full((2, 2), np.inf), np.full((2, 2), np.inf))
    assert none["n_common"] == 0 and math.isnan(none["mean_rel"])
