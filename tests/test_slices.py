"""Seismic slices: sample positions and values on the right pixels, opaque occluders culled by
three_pass, moving a slice, errors."""

from __future__ import annotations

import numpy as np
import pytest

import geocull as gc

RED_BLUE = [[1, 0, 0], [0, 0, 1]]


def checker_volume() -> gc.Volume:
    # 5 x 5 x 5 samples 10 m apart from (0, 0, -40): value (i + j + k) % 2.
    i, j, k = np.meshgrid(np.arange(5), np.arange(5), np.arange(5), indexing="ij")
    return gc.Volume(((i + j + k) % 2).astype(np.float32), origin=(0, 0, -40), spacing=(10, 10, 10), order="xyz")


def test_a_crossline_slice_puts_each_sample_on_its_pixel(renderer_small):
    vol = checker_volume()
    s = gc.Scene()
    s.add_slice(vol, "crossline", 2, cmap=RED_BLUE)
    # Head-on from -y, orthographic, 1 m per pixel over x in [-10, 50], z in [-50, 10].
    cam = gc.Camera.look_at((20, -100, -20), (20, 0, -20), projection="orthographic", ortho_height=60)
    img = renderer_small(60, 60).render(s, cam).image.astype(int)
    for i in range(5):
        for k in range(5):
            # Sample (i, 2, k) at x = 10 i, z = -40 + 10 k: column 10 + 10 i, row 50 - 10 k (nudged inside).
            col = min(10 + 10 * i, 49) if i == 4 else 10 + 10 * i
            row = max(50 - 10 * k, 10) if k == 4 else 50 - 10 * k
            px = img[min(row, 49), min(col, 49)]
            want_blue = (i + 2 + k) % 2 == 1
            assert (px[2] > px[0]) == want_blue, (i, k, px)


def test_an_opaque_slice_hides_the_horizon_behind_and_three_pass_culls_it(renderer_small):
    vol = checker_volume()
    s = gc.Scene()
    # A vertical fault plane behind the slice (seen from -y), two tiles, wholly covered by it.
    xs, zs = np.meshgrid(np.linspace(5, 35, 7), np.linspace(-35, -5, 7))
    v = np.c_[xs.ravel(), np.full(49, 30.0), zs.ravel()]
    f = [[r * 7 + c, r * 7 + c + 1, r * 7 + c + 8] for r in range(6) for c in range(6)]
    f += [[r * 7 + c, r * 7 + c + 8, r * 7 + c + 7] for r in range(6) for c in range(6)]
    h = s.add_mesh(v, f, kind="fault", tiles=2, color=(1, 1, 1))
    sl = s.add_slice(vol, "crossline", 1, cmap=RED_BLUE)
    cam = gc.Camera.look_at((20, -200, -20), (20, 0, -20), projection="orthographic", ortho_height=60)
    r = renderer_small(64, 64)
    full = r.render(s, cam, culling="none")
    s.set_visible(sl, False)
    alone = r.render(s, cam, culling="none")
    assert alone.coverage.sum() > 0
    s.set_visible(sl, True)
    tp = r.render(s, cam, culling="three_pass", pixel_threshold=0)
    np.testing.assert_array_equal(tp.image, full.image)
    tiles = s.tile_table()
    behind = tiles["object"] == h
    assert not tp.tile_drawn[behind].any()  # the horizon's tiles are culled
    assert (full.tile_pixels[behind] == 0).all()


def test_set_slice_index_moves_the_slice_and_keeps_its_id(renderer_small):
    vol = checker_volume()
    s = gc.Scene()
    a = s.add_slice(vol, "sample", 0, cmap=RED_BLUE, name="t0")
    z0 = s.bounds[0][2]
    s.set_slice_index(a, 3)
    assert s.object_ids() == [a]
    assert s.object_info(a)["name"] == "t0"
    assert s.bounds[0][2] == pytest.approx(z0 + 30)
    assert s.object_info(a)["clim"] == (0.0, 1.0)
    with pytest.raises(gc.InputError, match="^index"):
        s.set_slice_index(a, 5)
    with pytest.raises(gc.InputError, match="^axis"):
        s.add_slice(vol, "diagonal", 0)
    with pytest.raises(gc.InputError, match="^opacity"):
        s.add_slice(vol, 0, 0, opacity=1.5)
    with pytest.raises(gc.InputError, match="^volume"):
        s.add_slice(np.zeros((3, 3, 3)), 0, 0)  # type: ignore[arg-type]


def uniform_volume(value: float = 1.0) -> gc.Volume:
    return gc.Volume(np.full((5, 5, 5), value, np.float32), origin=(0, 0, -40), spacing=(10, 10, 10), order="xyz")


def test_a_lens_over_black_blends_to_the_expected_colour(renderer_small):
    # Two samples deep along the view (j = 1..2): two slices of colour c and opacity a over black
    # give c (1 - (1 - a)^2), unlit.
    s = gc.Scene()
    s.add_lens(uniform_volume(), ((0, 4), (1, 2), (0, 4)), cmap=[[0.2, 0.6, 1.0], [0.2, 0.6, 1.0]], clim=(0, 2),
               opacity=0.4)
    cam = gc.Camera.look_at((20, -100, -20), (20, 0, -20), projection="orthographic", ortho_height=60)
    res = renderer_small(60, 60).render(s, cam)
    want = np.array([0.2, 0.6, 1.0]) * (1 - 0.6 ** 2) * 255
    np.testing.assert_allclose(res.image[30, 30, :3], want, atol=2)
    assert not res.coverage.any()  # writes no depth
    assert res.stats["lens_slices_tested"] == 2 and res.stats["lens_slices_drawn"] == 2
    assert res.stats["lenses_hidden"] == 0


def test_a_lens_behind_a_slice_draws_nothing(renderer_small):
    s = gc.Scene()
    vol = checker_volume()
    s.add_lens(uniform_volume(), ((0, 4), (3, 4), (0, 4)), opacity=0.5)
    alone = gc.Scene()
    alone.add_slice(vol, "crossline", 0, cmap=RED_BLUE)
    s.add_slice(vol, "crossline", 0, cmap=RED_BLUE)  # in front of the lens, seen from -y, covering it
    cam = gc.Camera.look_at((20, -100, -20), (20, 0, -20), projection="orthographic", ortho_height=60)
    r = renderer_small(60, 60)
    res = r.render(s, cam, culling="three_pass", pixel_threshold=0)
    np.testing.assert_array_equal(res.image, r.render(alone, cam).image)
    assert res.stats["lenses_hidden"] == 1 and res.stats["lens_slices_drawn"] == 0
    with pytest.raises(gc.InputError, match="^opacity"):
        s.add_lens(vol, ((0, 4), (0, 4), (0, 4)), opacity=1.0)
    with pytest.raises(gc.InputError, match=r"^box\[1\]"):
        s.add_lens(vol, ((0, 4), (2, 2), (0, 4)))


def test_a_slice_matches_pyvista_slice_orthogonal(renderer_small):
    pv = pytest.importorskip("pyvista")
    import matplotlib

    rng = np.random.default_rng(3)
    vals = rng.normal(size=(9, 8, 7)).astype(np.float32)  # (nx, ny, nz), "xyz"
    vol = gc.Volume(vals, origin=(100, 200, -300), spacing=(10, 10, 5), order="xyz")
    s = gc.Scene()
    sl = s.add_slice(vol, "inline", 4, cmap="viridis", clim=(-2, 2))
    # PyVista's slice through the same samples: ImageData with the values as point data.
    img = pv.ImageData(dimensions=(9, 8, 7), spacing=(10, 10, 5), origin=(100, 200, -300))
    img.point_data["v"] = vals.ravel(order="F")
    ref_slice = img.slice(normal="x", origin=(140, 0, 0))
    # Same sample values on the plane (the lattice vertices are the volume's samples).
    assert len(s.geometry(sl)[0]) == 8 * 7
    np.testing.assert_allclose(np.sort(ref_slice.point_data["v"]), np.sort(vals[4].ravel()), atol=1e-6)
    # Coverage: head-on from +x, orthographic.
    # Coverage, head-on from +x, orthographic (edges off pixel centres: no rasterisation ties).
    cam = gc.Camera.look_at((500, 235, -285), (140, 235, -285), projection="orthographic", ortho_height=50)
    ours = renderer_small(80, 64).render(s, cam)
    ref = gc.Scene()
    ref.add_mesh(ref_slice.triangulate(), color=(1, 1, 1))
    vtk = gc.pyvista.reference_image(ref, cam, 80, 64, near=ours.near, far=ours.far)
    assert gc.compare.coverage_agreement(ours.depth, vtk["depth"]) >= 0.99
    # 1 m pixels whose centres fall on whole metres, so each sample lies on a pixel centre.
    cam = gc.Camera.look_at((500, 235.5, -285.5), (140, 235.5, -285.5), projection="orthographic", ortho_height=64)
    ours = renderer_small(80, 64).render(s, cam)
    # Colour: at each sample's pixel, matplotlib's colour for its value times the (constant, head-on)
    # shading, which a flat white slice gives: within 3/255 (8-bit rounding of both images).
    white = gc.Scene()
    white.add_mesh(*s.geometry(sl), color=(1, 1, 1))
    shade = renderer_small(80, 64).render(white, cam).image[..., :3].astype(float) / 255
    lut = matplotlib.colormaps["viridis"]
    view = cam.view_matrix()
    for j in range(1, 7):
        for k in range(1, 6):
            # Sample (4, j, k) projected: orthographic, 64 m over 64 rows and 80 m over 80 columns.
            q = view @ np.array([140.0, 200 + 10 * j, -300 + 5 * k, 1.0])
            col = int((q[0] / 40 + 1) / 2 * 80)
            row = int((1 - q[1] / 32) / 2 * 64)
            t = np.clip((vals[4, j, k] + 2) / 4, 0, 1)
            want = np.array(lut(min(int(t * 256), 255))[:3]) * shade[row, col]
            got = ours.image[row, col, :3] / 255
            assert np.abs(got - want).max() <= 3 / 255, (j, k, got, want)


def test_a_salt_body_under_a_horizon_is_culled_by_three_pass(renderer_small):
    # A ball of radius 30 m (distance field) centred at (50, 50, -60), under a horizon at z = -10.
    x, y, z = np.meshgrid(np.linspace(0, 100, 21), np.linspace(0, 100, 21), np.linspace(-120, 0, 25), indexing="ij")
    d = np.sqrt((x - 50) ** 2 + (y - 50) ** 2 + (z + 60) ** 2).astype(np.float32)
    vol = gc.Volume(d, origin=(0, 0, -120), spacing=(5, 5, 5), order="xyz")
    s = gc.Scene()
    salt = s.add_isosurface(vol, 30.0, tiles=4, color=(0.9, 0.8, 0.5))
    assert s.object_info(salt)["kind"] == "isosurface"
    v, f = s.geometry(salt)
    r = np.linalg.norm(v - [50, 50, -60], axis=1)
    assert abs(r.mean() - 30) < 0.5 and len(f) == len(gc.iso.extract_isosurface(vol, 30.0)[1])
    s.add_heightfield(np.full((11, 11), -10.0), origin=(-50, -50), spacing=(20, 20), tiles=(2, 2))
    top = gc.Camera.look_at((50, 40, 300), (50, 50, -60))
    rr = renderer_small(64, 48)
    none = rr.render(s, top, culling="none")
    tp = rr.render(s, top, culling="three_pass", pixel_threshold=0)
    np.testing.assert_array_equal(tp.image, none.image)
    assert not tp.tile_drawn[s.tile_table()["object"] == salt].any()
    # Seen from the side, below the horizon, it is drawn.
    side = rr.render(s, gc.Camera.look_at((50, -200, -60), (50, 50, -60)), culling="three_pass", pixel_threshold=0)
    assert side.tile_drawn[s.tile_table()["object"] == salt].any()


def test_a_translucent_slice_blends_and_never_occludes(renderer_small):
    s = gc.Scene()
    s.add_slice(uniform_volume(), "crossline", 1, cmap=[[0.2, 0.6, 1.0], [0.2, 0.6, 1.0]], clim=(0, 2), opacity=0.5)
    cam = gc.Camera.look_at((20, -100, -20), (20, 0, -20), projection="orthographic", ortho_height=60)
    res = renderer_small(60, 60).render(s, cam, culling="three_pass", pixel_threshold=0)
    np.testing.assert_allclose(res.image[30, 30, :3], np.array([0.2, 0.6, 1.0]) * 0.5 * 255, atol=2)
    assert not res.coverage.any() and res.stats["lens_slices_drawn"] >= 1


def test_moving_a_slice_rewrites_it_in_place_with_the_image_of_a_fresh_upload():
    # A horizon, a fault and two slices of a random cube whose sample plane 3 has no-data samples.
    rng = np.random.default_rng(5)
    vals = rng.normal(size=(12, 10, 8)).astype(np.float32)
    vals[2:6, 3:7, 3] = np.nan
    vol = gc.Volume(vals, origin=(0, 0, -70), spacing=(10, 10, 10), order="xyz")
    s = gc.Scene()
    s.add_heightfield(np.full((12, 10), -75.0), origin=(0, 0), spacing=(10, 10), tiles=(2, 2))
    xs, zs = np.meshgrid(np.linspace(0, 110, 6), np.linspace(-70, 0, 5))
    v = np.c_[xs.ravel(), np.full(30, 85.0), zs.ravel()]
    s.add_mesh(v, [[r * 6 + c, r * 6 + c + 1, r * 6 + c + 7] for r in range(4) for c in range(5)], kind="fault")
    inline = s.add_slice(vol, "inline", 3, cmap="seismic")
    tslice = s.add_slice(vol, "sample", 1, cmap="gray")
    cam = gc.Camera.orbit(target=(55, 45, -35), azimuth=200, elevation=35, distance=300)
    r = gc.Renderer(64, 48)
    r.render(s, cam)

    def check(culling: str, patched: int) -> None:
        got = r.render(s, cam, culling=culling, pixel_threshold=0)
        assert got.stats["objects_patched"] == patched
        fresh = gc.Renderer(64, 48).render(s, cam, culling=culling, pixel_threshold=0)
        assert fresh.stats["objects_patched"] == 0
        np.testing.assert_array_equal(got.image, fresh.image)
        np.testing.assert_array_equal(got.depth, fresh.depth)

    s.set_slice_index(inline, 7)
    check("none", 1)
    s.set_slice_index(inline, 8)  # two moves of one slice and one of another between frames
    s.set_slice_index(inline, 5)
    s.set_slice_index(tslice, 2)
    check("three_pass", 2)
    assert r.render(s, cam).stats["objects_patched"] == 0  # nothing changed
    s.set_slice_index(tslice, 3)  # the no-data colour where the samples are NaN
    check("temporal", 1)
    s.add_slice(vol, "crossline", 4)  # an object added: a full upload
    s.set_slice_index(inline, 6)
    check("none", 0)


def test_moving_a_slice_keeps_the_horizon_trees_of_the_height_fields():
    # Horizon culling's trees belong to their height fields: another object's change (a moved
    # slice) rebuilds none of them, and the frame is the one a fresh renderer draws.
    rng = np.random.default_rng(2)
    s = gc.Scene()
    for depth in (-30.0, -60.0):
        s.add_heightfield(depth + rng.normal(size=(20, 20)).cumsum(0), origin=(0, 0), spacing=(6, 6), tiles=(2, 2))
    vol = gc.Volume(rng.normal(size=(20, 20, 10)).astype(np.float32), origin=(0, 0, -90), spacing=(6, 6, 10),
                    order="xyz")
    sl = s.add_slice(vol, "crossline", 3)
    cam = gc.Camera.orbit(target=(57, 57, -45), azimuth=160, elevation=20, distance=250)
    r = gc.Renderer(48, 40)
    assert r.render(s, cam, culling="horizon").stats["trees_built"] == 2
    s.set_slice_index(sl, 12)
    got = r.render(s, cam, culling="horizon")
    assert got.stats["trees_built"] == 0
    np.testing.assert_array_equal(got.image, gc.Renderer(48, 40).render(s, cam, culling="horizon").image)
    s.add_heightfield(np.full((5, 5), -80.0), origin=(10, 10), spacing=(5, 5))  # a new one: its tree only
    assert r.render(s, cam, culling="horizon").stats["trees_built"] == 1
