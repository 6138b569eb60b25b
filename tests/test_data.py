"""geocull.data: scene generators and sample data (pure numpy; build() needs the extension)."""

import itertools
import math

import numpy as np
import pytest

from geocull import data


@pytest.fixture(scope="module")
def small():
    return data.gullfaks_like(nx=40, ny=30, n_horizons=4, n_faults=3, fault_triangles=(100, 400), seed=3)


def test_shapes_and_counts(small):
    assert len(small.horizons) == 4 and len(small.faults) == 3
    for h in small.horizons:
        assert h["z"].shape == (30, 40) and h["z"].dtype == np.float64
        assert len(h["origin"]) == 2 and len(h["spacing"]) == 2
        assert all(0.0 <= c <= 1.0 for c in h["color"])
    for f in small.faults:
        v, fc = f["vertices"], f["faces"]
        assert v.ndim == 2 and v.shape[1] == 3 and v.dtype == np.float64
        assert fc.dtype == np.int64 and fc.shape[1] == 3
        assert 100 <= len(fc) <= 400
        assert fc.min() >= 0 and fc.max() < len(v)
        assert np.isfinite(v).all()
    n_cells = 2 * 39 * 29
    assert small.n_horizon_triangles <= 4 * n_cells
    assert small.n_fault_triangles == sum(len(f["faces"]) for f in small.faults)
    assert small.n_triangles == small.n_horizon_triangles + small.n_fault_triangles


def test_horizons_stacked_downwards(small):
    zs = [h["z"] for h in small.horizons]
    for upper, lower in itertools.pairwise(zs):
        both = np.isfinite(upper) & np.isfinite(lower)
        assert (upper[both] > lower[both]).all()


def test_faults_inside_footprint_and_cross_stack(small):
    xmin, xmax, ymin, ymax, zmin, zmax = small.bounds
    top = max(np.nanmax(h["z"]) for h in small.horizons)
    bot = min(np.nanmin(h["z"]) for h in small.horizons)
    for f in small.faults:
        v = f["vertices"]
        assert v[:, 0].min() >= xmin and v[:, 0].max() <= xmax
        assert v[:, 1].min() >= ymin and v[:, 1].max() <= ymax
        assert v[:, 2].max() > top and v[:, 2].min() < bot


def test_holes_present():
    spec = data.gullfaks_like(nx=60, ny=60, n_horizons=3, n_faults=0, seed=1)
    assert np.isnan(spec.horizons[1]["z"]).any()
    assert not np.isnan(spec.horizons[0]["z"]).any()
    no_holes = data.gullfaks_like(nx=60, ny=60, n_horizons=3, n_faults=0, seed=1, holes=False)
    assert not any(np.isnan(h["z"]).any() for h in no_holes.horizons)


def test_determinism():
    a = data.stacked_test_scene(n=32, seed=5)
    b = data.stacked_test_scene(n=32, seed=5)
    c = data.stacked_test_scene(n=32, seed=6)
    for ha, hb in zip(a.horizons, b.horizons, strict=True):
        np.testing.assert_array_equal(ha["z"], hb["z"])
    for fa, fb in zip(a.faults, b.faults, strict=True):
        np.testing.assert_array_equal(fa["vertices"], fb["vertices"])
        np.testing.assert_array_equal(fa["faces"], fb["faces"])
    assert not np.array_equal(a.horizons[0]["z"], c.horizons[0]["z"], equal_nan=True)


def test_stacked_test_scene():
    s = data.stacked_test_scene()
    assert len(s.horizons) == 3 and len(s.faults) == 2
    assert s.horizons[0]["z"].shape == (64, 64)
    assert len(data.stacked_test_scene(with_faults=False).faults) == 0


def test_default_scene_size_documented():
    # The benchmark scene: ~3.9 M triangles (kept out of the fast path: only counts, no rendering).
    spec = data.gullfaks_like()
    assert len(spec.horizons) == 11 and len(spec.faults) == 16
    assert 3.7e6 < spec.n_triangles < 4.1e6


def test_heightfield_mesh_drops_hole_triangles():
    z = np.zeros((3, 4))
    v, f = data.heightfield_mesh(z, origin=(10.0, 20.0), spacing=(2.0, 3.0))
    assert v.shape == (12, 3) and f.shape == (2 * 3 * 2, 3)
    np.testing.assert_allclose(v[5], [12.0, 23.0, 0.0])  # j=1, i=1
    z[1, 1] = np.nan
    _, f2 = data.heightfield_mesh(z)
    assert not (f2 == 5).any()
    assert len(f2) == 12 - 6  # the six triangles around an interior vertex are gone


def test_mesh_scene(small):
    ms = small.mesh_scene()
    assert ms.object_ids() == list(range(7))
    assert ms.object_info(4)["kind"] == "fault"
    v, f = ms.geometry(0)
    assert v.shape == (1200, 3) and f.shape[1] == 3


def test_standard_views(small):
    views = data.standard_views(small)
    names = [n for n, _ in views]
    assert names == [
        "oblique_az045",
        "oblique_az135",
        "oblique_az225",
        "oblique_az315",
        "steep_az045",
        "low_az200",
        "top_down",
    ]
    b = np.asarray(small.bounds)
    centre = 0.5 * (b[0::2] + b[1::2])
    for name, kw in views:
        assert set(kw) >= {"eye", "target", "up", "fov_y"}
        np.testing.assert_allclose(kw["target"], centre)
        d = np.asarray(kw["eye"]) - centre
        el = math.degrees(math.asin(d[2] / np.linalg.norm(d)))
        expect = {"steep_az045": 60, "low_az200": 5, "top_down": 90}.get(name, 30)
        assert el == pytest.approx(expect, abs=1e-6)
        # every view is outside the bounding box
        assert not all(b[2 * i] <= kw["eye"][i] <= b[2 * i + 1] for i in range(3))
    # also accepts plain bounds
    assert len(data.standard_views(small.bounds)) == 7
    with pytest.raises(ValueError, match="spec_or_bounds"):
        data.standard_views((0, 1, 2))


def test_pesco_synthetic():
    vals, origin, spacing = data.pesco_synthetic(21)
    assert vals.shape == (21, 21, 21) and vals.dtype == np.float32
    assert origin == (-5.0, -5.0, -5.0)
    assert spacing == pytest.approx((0.5, 0.5, 0.5))

    def f(x, y, z):
        return math.sin(x * y * z / 8) + math.cos((x - 2) * (y - 2) * (z - 2))

    # values[k, j, i] = f(x_i, y_j, z_k): x_i = -5 + 0.5 i
    i, j, k = 3, 12, 17
    x, y, z = -5 + 0.5 * i, -5 + 0.5 * j, -5 + 0.5 * k
    assert vals[k, j, i] == pytest.approx(f(x, y, z), abs=1e-6)
    assert vals[10, 10, 10] == pytest.approx(math.cos(-8.0), abs=1e-6)


def test_jacksboro_dem():
    z, origin, spacing = data.jacksboro_dem()
    assert z.shape == (344, 403) and z.dtype == np.float64
    assert 200 < np.nanmin(z) and np.nanmax(z) < 1200
    dx, dy = spacing
    assert 60 < dx < 80 and 85 < dy < 100  # 3 arc-seconds at 36.6° N, in metres
    assert origin == (0.0, 0.0)


def test_topobathy():
    z, origin, spacing = data.topobathy()
    assert z.shape == (91, 120) and z.dtype == np.float64
    assert np.nanmin(z) < 0 < np.nanmax(z)
    assert all(1000 < s < 5000 for s in spacing)


def test_triangle_count_matches_mesh_scene(small):
    assert small.mesh_scene().n_triangles == small.n_triangles


def test_build_needs_extension(small):
    pytest.importorskip("geocull._geocull")
    import geocull as gc

    if not hasattr(gc, "Scene"):
        pytest.skip("geocull.Scene not exported yet")
    scene = small.build(tiles=(2, 2), coarse_factor=4)
    ids = scene.object_ids()
    assert len(ids) == len(small.horizons) + len(small.faults)
    assert scene.object_info(ids[-1])["kind"] == "fault"
    assert scene.n_triangles == small.n_triangles


def test_generator_and_sweep_arguments_raise_input_error():
    import geocull as gc
    from geocull import data
    from geocull.bench import report

    with pytest.raises(gc.InputError, match="^nx, ny"):
        data.gullfaks_like(nx=1)
    with pytest.raises(gc.InputError, match="^n:"):
        data.pesco_synthetic(1)
    with pytest.raises(gc.InputError, match="^scene_or_spec"):
        report.sweep(object())
