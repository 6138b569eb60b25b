"""No-data samples are never drawn as data: numpy masks (height fields, volumes; an error for mesh
vertices), ``null_value`` compared in the input's own dtype, and xtgeo's undefined values named in
the error when they arrive without their mask."""

from __future__ import annotations

import numpy as np
import pytest

import geocull as gc


def _z(shape=(5, 6)):
    ny, nx = shape
    return np.add.outer(np.arange(ny) * 0.5, np.arange(nx) * 0.25)


def _triangles_with(z, **kw):
    s = gc.Scene()
    s.add_heightfield(z, **kw)
    return s.n_triangles


def test_masked_heights_are_holes():
    z = _z()
    z[2, 3] = 1e6  # a huge value under the mask must not be drawn (nor rejected)
    zm = np.ma.masked_array(z, mask=np.zeros(z.shape, bool))
    zm[2, 3] = np.ma.masked
    holes = z.copy()
    holes[2, 3] = np.nan
    assert _triangles_with(zm) == _triangles_with(holes) < _triangles_with(_z())
    s, t = gc.Scene(), gc.Scene()
    s.add_heightfield(zm)
    t.add_heightfield(holes)
    assert np.nanmax(s.geometry(0)[0][:, 2]) < 10.0
    np.testing.assert_array_equal(s.geometry(0)[1], t.geometry(0)[1])


def test_masked_heights_of_any_dtype_and_mask_nomask():
    z = (_z() * 4).astype(np.int32)
    mask = np.zeros(z.shape, bool)
    mask[1, 1] = True
    zm = np.ma.masked_where(mask, z)
    holes = z.astype(float)
    holes[1, 1] = np.nan
    assert _triangles_with(zm) == _triangles_with(holes)
    # A masked array without a mask (mask=nomask) is plain data.
    assert _triangles_with(np.ma.masked_array(_z())) == _triangles_with(_z())


def test_masked_mesh_vertices_are_an_error_naming_the_first():
    v = np.ma.masked_array(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 1]], float))
    v[2, 1] = np.ma.masked
    v[3, 0] = np.ma.masked
    with pytest.raises(gc.InputError, match=r"^vertices\[2, 1\].*masked"):
        gc.Scene().add_mesh(v, [[0, 1, 2], [1, 3, 2]])
    # unmasked masked arrays are accepted
    gc.Scene().add_mesh(np.ma.masked_array(v.data), [[0, 1, 2]])


def test_masked_volume_samples_are_nan():
    n = 9
    c = np.linspace(-1, 1, n)
    vals = np.sqrt(c[:, None, None] ** 2 + c[None, :, None] ** 2 + c[None, None, :] ** 2) - 0.5
    vm = np.ma.masked_array(vals.copy(), mask=np.zeros(vals.shape, bool))
    vm[0, 0, 0] = 1e6
    vm[0, 0, 0] = np.ma.masked
    v = gc.Volume(vm)
    root = v.nodes(0)
    assert root["max"][0] < 10.0  # the masked 1e6 is no data, not a value
    nan = vals.copy()
    nan[0, 0, 0] = np.nan
    w = gc.Volume(nan)
    for d in range(v.max_depth() + 1):
        np.testing.assert_array_equal(v.nodes(d)["max"], w.nodes(d)["max"])


def test_float32_null_value_matches_the_stored_value():
    z = _z().astype(np.float32)
    z[1, 2] = -999.1  # float32 cannot hold -999.1: the array holds -999.0999755859375
    holes = z.astype(float)
    holes[1, 2] = np.nan
    assert _triangles_with(z, null_value=-999.1) == _triangles_with(holes) < _triangles_with(_z())


def test_integer_null_value():
    z = (_z() * 4).astype(np.int16)
    z[3, 3] = -999
    holes = z.astype(float)
    holes[3, 3] = np.nan
    assert _triangles_with(z, null_value=-999) == _triangles_with(holes)
    # a non-integral null_value matches no integer sample (it is not rounded onto one)
    assert _triangles_with(z, null_value=-999.25) == _triangles_with(z.astype(float))


@pytest.mark.parametrize("undef", [1e30, 1e33])
def test_xtgeo_undefined_value_without_mask_is_named(undef):
    z = _z()
    z[1, 4] = undef
    with pytest.raises(gc.InputError, match=r"^z\[1, 4\]") as e:
        gc.Scene().add_heightfield(z)
    msg = str(e.value)
    assert "xtgeo" in msg and "null_value=" in msg and "masked array" in msg
    # an ordinary out-of-range value gets no such hint
    z[1, 4] = 1e20
    with pytest.raises(gc.InputError) as e:
        gc.Scene().add_heightfield(z)
    assert "xtgeo" not in str(e.value)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_null_value_1e30_works(dtype):
    z = _z().astype(dtype)
    z[1, 4] = 1e30
    holes = z.astype(float)
    holes[1, 4] = np.nan
    assert _triangles_with(z, null_value=1e30) == _triangles_with(holes)
