"""Walking-skeleton acceptance (issue 2): scenes whose image and depth are known by construction."""

import numpy as np
import pytest

import geocull as gc

BG = np.array([0, 0, 0, 255], dtype=np.uint8)


@pytest.fixture(scope="module")
def r64():
    return gc.Renderer(64, 64)


def flat(z=0.0, n=11, size=100.0, tiles=(2, 2), **kw):
    s = gc.Scene()
    d = size / (n - 1)
    s.add_heightfield(np.full((n, n), z), origin=(-size / 2, -size / 2), spacing=(d, d), tiles=tiles, **kw)
    return s


def top_down(h=100.0, fov=90.0):
    return gc.Camera.look_at((0, 0, h), (0, 0, 0), up=(0, 1, 0), fov_y=fov)


def test_flat_plane_from_above_covers_expected_pixels_with_exact_depth(r64):
    # 100 m plane, 100 m below a 90° camera: it fills exactly the middle 32 x 32 pixels.
    res = r64.render(flat(), top_down())
    cov = res.coverage
    expected = np.zeros((64, 64), bool)
    expected[16:48, 16:48] = True
    assert np.array_equal(cov, expected)
    np.testing.assert_allclose(res.depth[cov], 100.0, rtol=1e-3)
    assert np.all(np.isinf(res.depth[~cov]))
    assert np.all(res.image[~cov] == BG)
    assert np.all(res.image[cov][:, :3].max(axis=1) > 0)


def test_orthographic_depth_is_distance_along_the_view_axis(r64):
    s = flat(z=-7.0)
    cam = gc.Camera.look_at((0, 0, 50), (0, 0, -7), up=(0, 1, 0), projection="orthographic", ortho_height=200.0)
    res = r64.render(s, cam)
    cov = res.coverage
    assert cov.sum() == 32 * 32
    np.testing.assert_allclose(res.depth[cov], 57.0, rtol=1e-3)


def test_nan_hole_shows_as_empty_pixels(r64):
    # A 3 x 3 block of NaN samples in a 21 x 21 grid removes every cell touching it: a 40 m square
    # hole centred on the plane (cells touching samples 9..11 span x in [-20, 20]).
    n = 21
    z = np.zeros((n, n))
    z[9:12, 9:12] = np.nan
    s = gc.Scene()
    s.add_heightfield(z, origin=(-50, -50), spacing=(5, 5), tiles=(4, 4))
    res = r64.render(s, top_down())
    cov = res.coverage
    # Plane spans pixels 16..47; the hole spans x, y in [-20, 20] m = pixels 16+12.8 .. 16+19.2.
    assert not cov[30:34, 30:34].any()
    assert cov[16:26, 16:48].all() and cov[38:48, 16:48].all()
    # The 4 x 4 cells touching the block lose their triangles, except the two corner-cell triangles
    # (diagonal from sample (i, j) to (i+1, j+1)) that do not touch a NaN sample: 32 - 2 dropped.
    assert s.n_triangles == 2 * 20 * 20 - 30


def test_mesh_in_front_occludes_the_plane(r64):
    s = flat()
    # A red square 50 m above the plane (half way to the camera), 20 m wide.
    v = np.array([[-10, -10, 50], [10, -10, 50], [10, 10, 50], [-10, 10, 50]], float)
    f = np.array([[0, 1, 2], [0, 2, 3]])
    s.add_mesh(v, f, kind="fault", color=(1, 0, 0))
    res = r64.render(s, top_down())
    # 20 m at 50 m distance with a 90° fov over 64 px: 12.8 px around the centre.
    centre = res.depth[28:36, 28:36]
    np.testing.assert_allclose(centre, 50.0, rtol=1e-3)
    px = res.image[32, 32]
    assert px[0] > 0 and px[1] == 0 and px[2] == 0
    # Around it the plane is still visible at 100 m.
    np.testing.assert_allclose(res.depth[18, 18], 100.0, rtol=1e-3)


def test_result_shapes_and_dtypes():
    r = gc.Renderer(40, 30)
    res = r.render(flat(), top_down())
    assert res.image.shape == (30, 40, 4) and res.image.dtype == np.uint8
    assert res.depth.shape == (30, 40) and res.depth.dtype == np.float32
    assert res.tile_pixels.shape == (4,) and res.tile_pixels.dtype == np.uint32
    assert res.tile_drawn.shape == (4,) and res.tile_drawn.dtype == bool
    for k in ("triangles_drawn", "triangles_fine_total", "tiles_drawn", "total_ms", "draw_ms"):
        assert k in res.stats
    png = res._repr_png_()
    assert png.startswith(b"\x89PNG") and len(png) > 100


def test_dynamic_scene_visibility_translation_and_removal(r64):
    s = flat()
    v = np.array([[-10, -10, 50], [10, -10, 50], [10, 10, 50], [-10, 10, 50]], float)
    mid = s.add_mesh(v, np.array([[0, 1, 2], [0, 2, 3]]))
    base = r64.render(s, top_down())
    s.set_visible(mid, False)
    hidden = r64.render(s, top_down())
    np.testing.assert_allclose(hidden.depth[32, 32], 100.0, rtol=1e-3)
    s.set_visible(mid, True)
    s.translate(mid, (0, 0, -25))  # now 75 m from the camera
    moved = r64.render(s, top_down())
    np.testing.assert_allclose(moved.depth[32, 32], 75.0, rtol=1e-3)
    s.remove(mid)
    gone = r64.render(s, top_down())
    assert np.array_equal(gone.image, hidden.image)
    assert base.stats["triangles_fine_total"] == gone.stats["triangles_fine_total"] + 2


def test_input_errors_name_the_argument():
    s = gc.Scene()
    cases = [
        (lambda: s.add_heightfield(np.zeros(5)), "z"),
        (lambda: s.add_heightfield(np.zeros((3, 3)), spacing=(1, -1)), "spacing"),
        (lambda: s.add_heightfield(np.zeros((3, 3)), tiles=(3, 1)), "tiles"),
        (lambda: s.add_heightfield(np.zeros((3, 3)), coarse_factor=0.5), "coarse_factor"),
        (lambda: s.add_heightfield(np.zeros((3, 3)), color=(1, 2, 0)), "color"),
        (lambda: s.add_heightfield(np.array([["a", "b"], ["c", "d"]])), "z"),
        (lambda: s.add_mesh(np.zeros((3, 2)), np.zeros((1, 3), int)), "vertices"),
        (lambda: s.add_mesh(np.zeros((3, 3)), np.array([[0, 1, 3]])), "faces"),
        (lambda: s.add_mesh(np.zeros((3, 3)), np.array([[0, 1, -1]])), "faces"),
        (lambda: s.add_mesh(np.array([[0, 0, np.inf], [1, 0, 0], [0, 1, 0]]), np.array([[0, 1, 2]])), "vertices"),
        (lambda: gc.Camera.look_at((1, 2, 3), (1, 2, 3)), "target"),
        (lambda: gc.Camera.look_at((0, 0, 1), (0, 0, 0), fov_y=180), "fov_y"),
        (lambda: gc.Renderer(0, 10), "width"),
        (lambda: gc.Renderer(10, 10**6), "height"),
    ]
    for fn, arg in cases:
        with pytest.raises(gc.InputError) as e:
            fn()
        assert str(e.value).startswith(arg), (arg, str(e.value))
        assert isinstance(e.value, ValueError)


def test_render_argument_errors(r64):
    s, c = flat(), top_down()
    for kw, arg in [({"culling": "fast"}, "culling"), ({"pixel_threshold": -1}, "pixel_threshold"),
                    ({"prepass_scale": 0}, "prepass_scale"), ({"prepass_scale": 1.5}, "prepass_scale")]:
        with pytest.raises(gc.InputError, match=f"^{arg}"):
            r64.render(s, c, **kw)


def test_submodules_are_reachable_as_attributes():
    import sys

    assert callable(gc.compare.image_error) and callable(gc.data.gullfaks_like)
    assert callable(gc.bench.report.sweep) and callable(gc.bench.main)
    with pytest.raises(AttributeError):
        _ = gc.no_such_thing
    # PyVista (VTK) is not imported until gc.pyvista is used.
    if "pyvista" not in sys.modules:
        assert "vtk" not in sys.modules


def test_scene_wholly_nearer_than_the_near_plane_warns(r64):
    # A 1e-8 m wide plate 5e-7 m below the eye: nearer than the near-plane floor (1e-6), so no
    # pixel can be drawn. That is a warning, not a silent black frame.
    s = flat(size=1e-8, n=3, tiles=(1, 1))
    cam = gc.Camera.look_at((0, 0, 5e-7), (0, 0, 0), up=(0, 1, 0), fov_y=90.0)
    assert issubclass(gc.GeocullWarning, UserWarning)
    with pytest.warns(gc.GeocullWarning, match="near"):
        res = r64.render(s, cam)
    assert not res.coverage.any()
    # the same with a near plane given beyond the scene
    with pytest.warns(gc.GeocullWarning, match="near"):
        r64.render(flat(), gc.Camera.look_at((0, 0, 100.0), (0, 0, 0), up=(0, 1, 0), near=200.0))
    # an empty frame for other reasons (looking away, hidden objects) does not warn
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r64.render(flat(), gc.Camera.look_at((0, 0, 100.0), (0, 0, 200.0), up=(0, 1, 0)))
        hidden = flat()
        hidden.set_visible(0, False)
        r64.render(hidden, top_down())
        r64.render(flat(), top_down())


def test_height_fields_cost_their_heights_not_their_triangles():
    # Lattice tiles (gpu::geometry::Plan): a hole-free height field's draws are patterns shared by
    # every tile of one shape, rebuilt by the vertex stage from the normal map's heights (8 bytes
    # per sample), so its GPU bytes stay far below vertices + indices (~40 bytes per triangle).
    # The same triangles as a mesh have vertices of their own. Both render alike.
    n = 201
    s = flat(n=n, tiles=(5, 5))
    r = gc.Renderer(32, 32)
    res = r.render(s, top_down())
    tris = res.stats["triangles_fine_total"]
    assert tris == 2 * (n - 1) ** 2
    assert r.gpu_bytes < 8 * tris
    # On the host, the tiles of one shape share their triangle lists (lod::share_indices): the
    # vertices' 12 bytes (about 6 per triangle) remain, not the ~16 of the lists.
    assert s.host_bytes < 8 * tris
    v, f = s.geometry(s.object_ids()[0])
    m = gc.Scene()
    m.add_mesh(v, f, priority=4)  # a height field's depth-tie priority: drawn at the same depth
    rm = gc.Renderer(32, 32)
    res_m = rm.render(m, top_down())
    assert rm.gpu_bytes > 30 * tris
    assert np.array_equal(res.coverage, res_m.coverage)
    np.testing.assert_array_equal(res.depth, res_m.depth)


@pytest.mark.parametrize("n, lead", [(61, False), (121, True)])
def test_height_fields_coloured_by_data_are_lattice_tiles_too(n, lead):
    # A flat plane seen from above shades the same from its fine surface (height field) as from
    # its facets (mesh), so the two images agree: the lattice tiles' values per sample
    # (gpu::geometry::SceneGeometry::sample_values, no data included) are the vertices'. With
    # 121 x 121 samples behind a small field out of view, the plane's heights and values start
    # mid-row and run over into the next row of their textures (8192 words a row).
    vals = np.add.outer(np.linspace(0.0, 1.0, n), np.linspace(0.0, 2.0, n))
    vals[20:25, 30:40] = np.nan
    s = gc.Scene()
    if lead:
        s.add_heightfield(np.zeros((7, 7)), origin=(500, 500), spacing=(1, 1), values=np.ones((7, 7)),
                          cmap="viridis", clim=(0.0, 3.0))
    d = 100 / (n - 1)
    s.add_heightfield(np.zeros((n, n)), origin=(-50, -50), spacing=(d, d), tiles=(3, 3), values=vals,
                      cmap="viridis", clim=(0.0, 3.0))
    r = gc.Renderer(64, 64)
    res = r.render(s, top_down())
    tris = res.stats["triangles_fine_total"]
    assert r.gpu_bytes < 12 * tris
    v, f = s.geometry(s.object_ids()[-1])
    m = gc.Scene()
    m.add_mesh(v, f, values=vals.ravel()[np.ravel_multi_index(
        (np.rint((v[:, 1] + 50) / d).astype(int), np.rint((v[:, 0] + 50) / d).astype(int)), (n, n))],
        cmap="viridis", clim=(0.0, 3.0))
    rm = gc.Renderer(64, 64)
    res_m = rm.render(m, top_down())
    assert rm.gpu_bytes > 30 * tris
    assert np.array_equal(res.coverage, res_m.coverage)
    # The vertices agree to a few ulps (rebuilt in f32 by the vertex stage), so a pixel whose
    # value lies on a colour-map row boundary may take the next row: at most 2 levels, rarely.
    diff = np.abs(res.image.astype(int) - res_m.image.astype(int)).max(axis=-1)
    assert diff.max() <= 2 and (diff > 0).mean() < 0.01
    assert len(np.unique(res.image[res.coverage].reshape(-1, 4), axis=0)) > 20
