"""Volumes as they come (issue 16): ``Volume(values, origin, spacing, order=, z_positive=, rotation=)``,
xarray DataArrays by dim name, and ``geocull.extract_isosurface``.

What is checked:
- order="xyz" (segyio / xtgeo axis order) gives the same volume as the same samples in (nz, ny, nx),
  for contiguous, transposed-view, reversed and float64 inputs (the core reads strides itself);
- z_positive="down": a depth cube holding a dome (shallowest at the centre) renders right way up:
  the apex is the highest point of the surface, at world z = -(apex depth), and seen from the side
  the surface is highest in the middle of the image; a negative dz says to use z_positive="down";
- rotation: a rotated volume's isosurface renders like its extracted mesh in a scene, implicit
  culling still gives the unculled image, and the mesh is the unrotated one turned about the origin;
- extract_isosurface: the renderer's triangles (count = surface_triangles of culling="none"),
  welded (a closed sphere has every edge twice), world float64 / int64;
- xarray: dims found by name in any order, origin / spacing from regular coordinates (a
  decreasing coordinate reversed), depth dims default to z_positive="down", line-number dims
  need origin and spacing, irregular coordinates are an InputError.
"""

from __future__ import annotations

import numpy as np
import pytest

import geocull as gc

W = H = 96


@pytest.fixture(scope="module")
def renderer() -> gc.Renderer:
    return gc.Renderer(W, H)


def sphere_zyx(n: int = 24, r: float = 8.0, dtype=np.float32) -> np.ndarray:
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(np.float64)
    c = (n - 1) / 2
    return (np.sqrt((x - c) ** 2 + (y - c * 0.9) ** 2 + (z - c * 1.1) ** 2) - r).astype(dtype)


def test_xyz_order_and_strides_give_the_same_volume():
    v = sphere_zyx()
    ref32 = gc.extract_isosurface(gc.Volume(v, (10.0, 20.0, 30.0), (1.0, 2.0, 3.0)), 0.0)
    v64 = v.astype(np.float64) + 1e6  # float64: residuals about the midrange, read strided as well
    ref64 = gc.extract_isosurface(gc.Volume(v64, (10.0, 20.0, 30.0), (1.0, 2.0, 3.0)), 1e6)
    xyz = v.transpose(2, 1, 0)  # values[i, j, k]
    for a, order, ref, w in [
        (np.ascontiguousarray(xyz), "xyz", ref32, 0.0),
        (xyz, "xyz", ref32, 0.0),  # a transposed view: read with its strides
        (np.asfortranarray(v), "zyx", ref32, 0.0),
        (np.ascontiguousarray(v[::-1])[::-1], "zyx", ref32, 0.0),  # negative strides
        (v64.transpose(2, 1, 0), "xyz", ref64, 1e6),
        (np.asfortranarray(v64)[:, ::-1][:, ::-1], "zyx", ref64, 1e6),
    ]:
        vol = gc.Volume(a, (10.0, 20.0, 30.0), (1.0, 2.0, 3.0), order=order)  # type: ignore[arg-type]
        assert vol.shape == v.shape
        got = gc.extract_isosurface(vol, w)
        np.testing.assert_array_equal(got[0], ref[0])
        np.testing.assert_array_equal(got[1], ref[1])
    with pytest.raises(gc.InputError, match=r'^order is "yxz"; expected "zyx"'):
        gc.Volume(v, order="yxz")  # type: ignore[arg-type]
    with pytest.raises(gc.InputError, match=r'^z_positive is "Down"'):
        gc.Volume(v, z_positive="Down")  # type: ignore[arg-type]


def dome_depth_cube(n: int = 33, apex: float = 1200.0):
    """A depth cube (values[i, j, k], k = depth index, z positive down) whose 0-isosurface is a dome:
    depth(x, y) = apex + 0.004 * r^2, shallowest (apex) at the centre."""
    x0, y0, z0, d, dz = 5000.0, 8000.0, 1000.0, 25.0, 10.0
    i, j, k = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
    x, y, depth = x0 + i * d, y0 + j * d, z0 + k * dz
    cx, cy = x0 + (n - 1) / 2 * d, y0 + (n - 1) / 2 * d
    dome = apex + 0.004 * ((x - cx) ** 2 + (y - cy) ** 2)
    return (depth - dome).astype(np.float32), (x0, y0, z0), (d, d, dz), (cx, cy)


def test_depth_positive_down_renders_right_way_up(renderer):
    values, origin, spacing, (cx, cy) = dome_depth_cube()
    vol = gc.Volume(values, origin, spacing, order="xyz", z_positive="down")
    (lo, hi) = vol.bounds
    assert lo[2] == pytest.approx(-(1000.0 + 32 * 10.0)) and hi[2] == pytest.approx(-1000.0)
    v, f = gc.extract_isosurface(vol, 0.0)
    top = v[np.argmax(v[:, 2])]
    assert top[2] == pytest.approx(-1200.0, abs=10.0)  # the apex, at z = -depth
    assert abs(top[0] - cx) < 30 and abs(top[1] - cy) < 30
    assert v[:, 2].min() < -1250.0  # the flanks go deeper
    # Seen from the side (looking north, z up): the surface's top edge is highest in the middle.
    cam = gc.Camera.look_at((cx, cy - 1200.0, -1250.0), (cx, cy, -1250.0), fov_y=20.0)
    res = renderer.render_isosurface(vol, 0.0, cam, culling="none")
    cov = res.coverage
    cols = np.nonzero(cov.any(axis=0))[0]
    assert len(cols) > W // 3
    top_row = np.array([np.argmax(cov[:, c]) for c in cols])  # row 0 = top of the image
    mid = cols[np.argmin(top_row)]
    assert abs(mid - W / 2) < W / 8, "the dome's apex must be the highest point, in the middle"
    assert top_row.min() < top_row[0] and top_row.min() < top_row[-1]
    # The same cube given upside down by hand (the old way) agrees.
    by_hand = gc.Volume(np.ascontiguousarray(values[:, :, ::-1]), (origin[0], origin[1], -1320.0), spacing,
                        order="xyz")
    np.testing.assert_array_equal(gc.extract_isosurface(by_hand, 0.0)[1].shape, f.shape)
    np.testing.assert_allclose(np.sort(gc.extract_isosurface(by_hand, 0.0)[0][:, 2]), np.sort(v[:, 2]))
    with pytest.raises(gc.InputError, match=r'^spacing: component 2 is -10; .*z_positive="down"'):
        gc.Volume(values, origin, (25.0, 25.0, -10.0), order="xyz")


def test_rotated_volume_renders_like_its_mesh(renderer):
    v = sphere_zyx(n=20, r=6.0) + 0.0
    v[:, :, :4] = 5.0  # an asymmetric slab so that the rotation shows
    origin, spacing = (100.0, 200.0, 0.0), (1.0, 1.5, 1.0)
    plain = gc.Volume(v, origin, spacing)
    vol = gc.Volume(v, origin, spacing, rotation=35.0)
    assert vol.rotation == 35.0
    pv, pf = gc.extract_isosurface(plain, 0.0)
    rv, rf = gc.extract_isosurface(vol, 0.0)
    np.testing.assert_array_equal(pf, rf)
    t = np.radians(35.0)
    u, w = pv[:, 0] - 100.0, pv[:, 1] - 200.0
    np.testing.assert_allclose(rv[:, 0], 100.0 + np.cos(t) * u - np.sin(t) * w, atol=1e-9)
    np.testing.assert_allclose(rv[:, 1], 200.0 + np.sin(t) * u + np.cos(t) * w, atol=1e-9)
    lo, hi = vol.bounds
    assert np.all(rv >= np.array(lo) - 1e-9) and np.all(rv <= np.array(hi) + 1e-9)
    s = gc.Scene()
    s.add_mesh(rv, rf, kind="isosurface")
    c = np.array(vol.center)
    for eye in [c + (0.0, 0.0, 60.0), c + (40.0, -30.0, 20.0), c + (-35.0, 10.0, -15.0)]:
        cam = gc.Camera.look_at(eye, c, up=(0, 1, 0) if eye[2] == c[2] + 60 else (0, 0, 1), fov_y=40.0)
        none = renderer.render_isosurface(vol, 0.0, cam, culling="none")
        imp = renderer.render_isosurface(vol, 0.0, cam, culling="implicit")
        np.testing.assert_array_equal(imp.image, none.image)
        mesh = renderer.render(s, cam)
        assert none.stats["surface_triangles"] == len(rf)
        assert gc.compare.coverage_agreement(none.depth, mesh.depth) > 0.995
    with pytest.raises(gc.InputError, match="^rotation is inf"):
        gc.Volume(v, rotation=np.inf)


def test_extract_isosurface_is_the_renderers_surface(renderer):
    vol = gc.Volume(sphere_zyx(n=28, r=9.0), (0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    v, f = gc.extract_isosurface(vol, 0.0)
    assert v.dtype == np.float64 and f.dtype == np.int64 and v.shape[1] == 3 and f.shape[1] == 3
    assert f.min() >= 0 and f.max() == len(v) - 1  # every vertex used: welded, none dangling
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    assert np.all(counts == 2), "a closed surface: every edge shared by two triangles"
    cam = gc.Camera.look_at((40.0, 30.0, 25.0), vol.center)
    res = renderer.render_isosurface(vol, 0.0, cam, culling="none")
    assert res.stats["surface_triangles"] == len(f)
    assert len(gc.extract_isosurface(vol, 1e6)[1]) == 0
    with pytest.raises(gc.InputError, match="^isovalue"):
        gc.extract_isosurface(vol, float("nan"))
    with pytest.raises(gc.InputError, match="^volume: expected a geocull.Volume"):
        gc.extract_isosurface(np.zeros((3, 3, 3)), 0.0)  # type: ignore[arg-type]


def test_xarray_dataarrays_by_dim_name():
    xr = pytest.importorskip("xarray")
    values, origin, spacing, _ = dome_depth_cube(n=17)
    ref = gc.extract_isosurface(gc.Volume(values, origin, spacing, order="xyz", z_positive="down"), 0.0)
    x = origin[0] + spacing[0] * np.arange(17)
    y = origin[1] + spacing[1] * np.arange(17)
    d = origin[2] + spacing[2] * np.arange(17)
    da = xr.DataArray(values, dims=("x", "y", "depth"), coords={"x": x, "y": y, "depth": d})
    for arr in [da, da.transpose("depth", "x", "y"), da.isel(y=slice(None, None, -1))]:
        got = gc.extract_isosurface(gc.Volume(arr), 0.0)
        np.testing.assert_array_equal(got[1].shape, ref[1].shape)
        np.testing.assert_allclose(np.sort(got[0], axis=0), np.sort(ref[0], axis=0), atol=1e-6)
    vol = gc.Volume(da)
    assert vol.origin == pytest.approx((origin[0], origin[1], -(origin[2] + 16 * spacing[2])))
    # segyio-style dims: line numbers are not metres
    seis = xr.DataArray(values, dims=("inline", "crossline", "twt"),
                        coords={"inline": np.arange(100, 117), "crossline": np.arange(7, 24)})
    with pytest.raises(gc.InputError, match="^spacing: the DataArray's 'inline' coordinate holds line numbers"):
        gc.Volume(seis)
    vol = gc.Volume(seis, origin=origin, spacing=spacing)
    assert vol.bounds[1][2] == pytest.approx(-origin[2])  # twt: z positive down by default
    bad = da.assign_coords(x=x ** 1.01)
    with pytest.raises(gc.InputError, match="'x' is not regularly spaced"):
        gc.Volume(bad)
    with pytest.raises(gc.InputError, match="must name an x, a y and a z axis"):
        gc.Volume(xr.DataArray(values, dims=("a", "b", "c")))
    # order= given: read as a plain array
    plain = gc.Volume(xr.DataArray(values, dims=("a", "b", "c")), origin, spacing, order="xyz", z_positive="down")
    np.testing.assert_array_equal(gc.extract_isosurface(plain, 0.0)[0], ref[0])


def test_pickled_volumes_keep_rotation_and_layout():
    import pickle

    values, origin, spacing, _ = dome_depth_cube(n=17)
    vol = gc.Volume(values, origin, spacing, order="xyz", z_positive="down", rotation=21.0)
    back = pickle.loads(pickle.dumps(vol))
    assert (back.rotation, back.origin, back.spacing, back.shape) == (21.0, vol.origin, vol.spacing, vol.shape)
    np.testing.assert_array_equal(gc.extract_isosurface(back, 0.0)[0], gc.extract_isosurface(vol, 0.0)[0])
