"""Isosurfaces with implicit occluders: known answers on small volumes (<= 48^3, <= 128x128)."""

from __future__ import annotations

import os

import numpy as np
import pytest

import geocull as gc
from geocull import data

W = H = 96
# Where the implicit walk runs: a compute pass, or the host's cores (the same walk step for step).
WALKS = ("gpu", "cpu")


@pytest.fixture(scope="module")
def renderer():
    return gc.Renderer(W, H)


def grid(n, lo=-1.0, hi=1.0):
    h = (hi - lo) / (n - 1)
    c = lo + h * np.arange(n)
    return c[:, None, None], c[None, :, None], c[None, None, :], h


def sphere_volume(n=40, r=0.6):
    z, y, x = grid(n)[:3]
    h = 2.0 / (n - 1)
    vals = (np.sqrt(x * x + y * y + z * z) - r).astype(np.float32)
    return gc.Volume(vals, origin=(-1, -1, -1), spacing=(h, h, h))


def cam_around(az_deg, el_deg=20.0, dist=4.0, center=(0.0, 0.0, 0.0)):
    a, e = np.radians(az_deg), np.radians(el_deg)
    eye = np.array(center) + dist * np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    return gc.Camera.look_at(eye, center, up=(0, 0, 1), fov_y=40.0), eye


# ---- Volume


def test_volume_accepts_float32_float64_memmap_and_checks(tmp_path):
    v32 = np.random.default_rng(0).random((5, 6, 7), dtype=np.float32)
    v = gc.Volume(v32, origin=(1, 2, 3), spacing=(0.5, 1, 2))
    assert v.shape == (5, 6, 7)
    assert v.bounds == ((1, 2, 3), (1 + 6 * 0.5, 2 + 5, 3 + 4 * 2))
    assert v.max_depth() == 3  # 6 cells along x -> 8 = 2^3
    gc.Volume(v32.astype(np.float64))
    mm = np.lib.format.open_memmap(tmp_path / "v.npy", mode="w+", dtype=np.float32, shape=(5, 6, 7))
    mm[:] = v32
    vm = gc.Volume(mm)
    n = vm.nodes(0)
    assert n["min"][0] == pytest.approx(v32.min()) and n["max"][0] == pytest.approx(v32.max())
    gc.Volume(v32[:, :, ::2])  # non-contiguous: copied
    with pytest.raises(gc.InputError, match="values"):
        gc.Volume(np.zeros((4, 4)))
    with pytest.raises(gc.InputError, match="values"):
        gc.Volume(np.zeros((1, 4, 4)))
    with pytest.raises(gc.InputError, match="spacing"):
        gc.Volume(v32, spacing=(0, 1, 1))


def test_bad_arguments(renderer):
    v = sphere_volume(9)
    cam, _ = cam_around(30)
    with pytest.raises(gc.InputError, match="culling"):
        renderer.render_isosurface(v, 0.0, cam, culling="bogus")
    with pytest.raises(gc.InputError, match="cull_depth"):
        renderer.render_isosurface(v, 0.0, cam, cull_depth=v.max_depth() + 1)
    with pytest.raises(gc.InputError, match="isovalue"):
        renderer.render_isosurface(v, float("nan"), cam)
    with pytest.raises(gc.InputError, match="walk"):
        renderer.render_isosurface(v, 0.0, cam, walk="gpus")
    with pytest.raises(gc.InputError, match="walk"):
        renderer.render_isosurface(v, 0.0, cam, walk=1)  # type: ignore[arg-type]


def test_walk_runs_where_asked_and_auto_picks_the_host_on_a_cpu_adapter(renderer):
    v = sphere_volume(16)
    cam, _ = cam_around(30)
    on_cpu = "Cpu," in renderer.adapter_info
    assert renderer.render_isosurface(v, 0.0, cam, culling="none").stats["walk"] == "none"
    assert renderer.render_isosurface(v, 0.0, cam).stats["walk"] == ("cpu" if on_cpu else "gpu")
    for w in WALKS:
        res = renderer.render_isosurface(v, 0.0, cam, walk=w)
        assert res.stats["walk"] == w
        # the host's walk needs no submission and no read-back before the draw
        assert (res.stats["submissions"], res.stats["readbacks"]) == ((1, 0) if w == "cpu" else (2, 1))
        # it counts its rays (those entering the box, at most one per pixel) and their steps
        s = res.stats
        if w == "cpu":
            assert 0 < s["walk_rays"] <= W * H and s["walk_steps"] >= s["walk_rays"]
        else:
            assert (s["walk_rays"], s["walk_steps"]) == (0, 0)


# ---- Known answers


def test_volume_wholly_above_has_no_surface(renderer):
    v = gc.Volume(np.ones((20, 20, 20), np.float32))
    cam = gc.Camera.look_at((30, 25, 20), (10, 10, 10))
    for culling in ("implicit", "none"):
        res = renderer.render_isosurface(v, 0.0, cam, culling=culling)
        s = res.stats
        assert s["surface_triangles"] == 0 and s["nodes_visible"] == 0 and s["nodes_straddling"] == 0
        assert (res.image == np.array([0, 0, 0, 255], np.uint8)).all()
        assert np.isinf(res.depth).all()
    # Wholly below as well: everything is an occluder of one class, nothing is proven.
    res = renderer.render_isosurface(v, 2.0, cam, return_map=True)
    assert res.stats["surface_triangles"] == 0 and np.isinf(res.occlusion_map).all()


def test_sphere_back_half_culled_and_image_equal(renderer):
    v = sphere_volume(40, 0.6)
    md = v.max_depth()
    for az in (0.0, 130.0, 250.0):
        cam, eye = cam_around(az)
        ref = renderer.render_isosurface(v, 0.0, cam, culling="none")
        # Fine occluders (single cells) and nodes of 2 cells: the back half is hidden except near
        # the silhouette, where rays only graze the region below w.
        res = renderer.render_isosurface(v, 0.0, cam, culling="implicit", occluder_depth=md,
                                         cull_depth=md - 1, return_map=True, walk="gpu")
        host = renderer.render_isosurface(v, 0.0, cam, culling="implicit", occluder_depth=md,
                                          cull_depth=md - 1, return_map=True, walk="cpu")
        # the host's walk also places contours on this sparse surface (the compute walk only on
        # dense ones): the same image, from a subset of the cells the compute walk saw
        np.testing.assert_array_equal(host.image, ref.image)
        assert (host.tile_pixels <= res.tile_pixels).all()
        assert host.stats["surface_triangles"] <= res.stats["surface_triangles"]
        hm = host.occlusion_map
        assert (ref.depth[np.isfinite(hm)] <= hm[np.isfinite(hm)] * (1 + 1e-5)).all()
        s = res.stats
        # The image is identical: the method is conservative.
        assert np.array_equal(res.image, ref.image)
        assert np.array_equal(res.depth, ref.depth)
        assert s["surface_triangles"] < 0.75 * ref.stats["surface_triangles"]
        assert s["nodes_visible"] < 0.75 * s["nodes_straddling"]
        assert s["nodes_tested"] >= s["nodes_tested_cull_depth"] > 0
        # Nodes on the far side of the sphere are culled.
        cd = s["cull_depth"]
        cells = 2 ** (md - cd)
        h = v.spacing[0]
        centers = -1.0 + (res.nodes[:, 1:4] + 0.5) * cells * h
        vdir = eye / np.linalg.norm(eye)
        side = centers @ vdir
        back = side < -0.4
        assert back.sum() > 10
        assert not res.tile_drawn[back].any()
        # Every front node with surface pixels in the reference is drawn. (The sphere's surface is
        # sparse, so the walk places no contours; with them, rays stop right behind the surface
        # and a node whose only triangles are slivers covering no pixel centre may go undrawn.)
        front = side > 0.3
        assert res.tile_drawn[front].all()
        # The map never claims a depth nearer than the true surface.
        m = res.occlusion_map
        proven = np.isfinite(m)
        assert proven.sum() > 0.3 * np.isfinite(ref.depth).sum()
        assert (ref.depth[proven] <= m[proven] * (1 + 1e-5)).all()
        assert np.isfinite(ref.depth[proven]).all()


def test_occlusion_map_of_nested_boxes(renderer):
    # f = max(|x|, |y|, |z|) on [-1, 1]^3, w = 0.5: the surface is the box |.|_inf = 0.5; the region
    # below w is the inner box, above w the shell between it and the volume's box.
    n = 33
    z, y, x, h = grid(n)
    vals = np.maximum(np.maximum(np.abs(x), np.abs(y)), np.abs(z)).astype(np.float32)
    v = gc.Volume(vals, origin=(-1, -1, -1), spacing=(h, h, h))
    assert v.max_depth() == 5
    od = 4  # nodes of 2 cells (0.125 units)
    nodes = v.nodes(od)
    below = nodes["max"] < 0.5
    lo, hi = nodes["bbox_min"][below].min(0), nodes["bbox_max"][below].max(0)
    a = 0.375  # union of the Below nodes at depth 4 (samples at +-0.5 have f = 0.5, not < 0.5)
    assert np.allclose(lo, -a) and np.allclose(hi, a)
    cam = gc.Camera.look_at((0, 0, 5), (0, 0, 0), up=(0, 1, 0), projection="orthographic", ortho_height=2.4)
    res = renderer.render_isosurface(vals_volume := v, 0.5, cam, occluder_depth=od, cull_depth=3, return_map=True)
    m = res.occlusion_map
    px = -1.2 + (np.arange(W) + 0.5) * (2.4 / W)  # pixel centres (square image: same in y)
    inside = (np.abs(px)[None, :] < a) & (np.abs(px)[:, None] < a)
    # Proven exactly over the inner (Below) box, at its top face: entering the outer shell (above)
    # at z = 1 and then the inner box (below) means the surface z = 0.5 was crossed before z = a.
    assert np.array_equal(np.isfinite(m), inside)
    assert np.allclose(m[inside], 5 - a, atol=1e-3)
    # The true surface is in front of the map everywhere it is proven.
    assert (res.depth[inside] <= m[inside] + 1e-4).all()
    assert np.allclose(res.depth[inside], 4.5, atol=1e-3)
    ref = renderer.render_isosurface(vals_volume, 0.5, cam, culling="none", cull_depth=3)
    assert np.array_equal(res.image, ref.image)
    assert res.stats["nodes_visible"] < res.stats["nodes_straddling"]


def test_faces_prove_a_sheet_no_cell_can(renderer):
    # Below everywhere but the sample plane z = 8, above: the surface is two sheets (z = 7.5 and
    # 8.5) and no cell has 8 corners above, so no Above cell proves anything. The plane's cell
    # faces are uniform (all 4 corners above): a ray from above crosses Below cells, then the
    # upper sheet, then such a face, and stops there; the lower sheet behind it is not drawn.
    n = 17
    vals = np.full((n, n, n), -1.0, dtype=np.float32)
    vals[8] = 1.0
    v = gc.Volume(vals, origin=(0, 0, 0), spacing=(1, 1, 1))
    assert not (v.nodes(v.max_depth())["min"] > 0).any(), "no Above cell"
    cam = gc.Camera.look_at((8, 8, 40), (8, 8, 0), up=(0, 1, 0), projection="orthographic", ortho_height=20.0)
    ref = renderer.render_isosurface(v, 0.0, cam, culling="none")
    res = renderer.render_isosurface(v, 0.0, cam, return_map=True)
    np.testing.assert_array_equal(res.image, ref.image)
    np.testing.assert_array_equal(res.depth, ref.depth)
    px = 8 - 10 + (np.arange(W) + 0.5) * (20 / W)
    inside = ((px > 0) & (px < 16))[None, :] & ((px > 0) & (px < 16))[:, None]
    m = res.occlusion_map
    assert np.isfinite(m[inside]).all() and not np.isfinite(m[~inside]).any()
    assert np.allclose(m[inside], 40 - 8, atol=1e-2)  # the plane z = 8
    assert np.allclose(ref.depth[inside], 40 - 8.5, atol=1e-3)  # the upper sheet, in front
    # The upper sheet only: half the triangles (its cells' and no more).
    assert res.stats["surface_triangles"] == ref.stats["surface_triangles"] // 2


def test_eye_beside_the_volume_with_the_near_plane_at_its_floor():
    # The eye 0.18 outside the box, with box corners behind its plane: the near plane falls to
    # its floor (1e-6), where an f32 inverse view-projection gave the walk other rays than the
    # rasteriser's, and implicit lost 13 visible pixels along the image's top.
    rng = np.random.default_rng(0)
    vals = rng.normal(size=(6, 6, 6))
    vals = (np.sign(vals) * np.abs(vals) ** 0.5).astype(np.float32)
    v = gc.Volume(vals, origin=(0, 0, 0), spacing=(1, 1, 1))
    cam = gc.Camera.look_at((5.18, 2.5, 2.877), (2.5, 2.5, 2.5), up=(0, 0, 1), fov_y=50.0)
    r = gc.Renderer(48, 40)
    ref = r.render_isosurface(v, 0.0, cam, culling="none")
    assert ref.near == 1e-6
    res = r.render_isosurface(v, 0.0, cam)
    np.testing.assert_array_equal(res.image, ref.image)
    np.testing.assert_array_equal(res.depth, ref.depth)


def test_second_frame_reuses_patches(renderer):
    gc.iso.clear_cache(renderer)
    v = sphere_volume(24, 0.5)
    cam, _ = cam_around(45)
    a = renderer.render_isosurface(v, 0.0, cam)
    assert a.stats["patches_extracted"] == a.stats["nodes_visible"] > 0
    b = renderer.render_isosurface(v, 0.0, cam)
    assert b.stats["patches_extracted"] == 0 and b.stats["patches_cached"] == b.stats["nodes_visible"]
    assert np.array_equal(a.image, b.image)
    c = renderer.render_isosurface(v, 0.0, cam, cache=False)
    assert c.stats["patches_cached"] == 0 and np.array_equal(a.image, c.image)


def test_pesco_synthetic_conservative_over_views_and_depths(renderer):
    vals, origin, spacing = data.pesco_synthetic(40)
    v = gc.Volume(vals, origin=origin, spacing=spacing)
    md = v.max_depth()
    for az in (20.0, 200.0):
        cam, _ = cam_around(az, 25.0, dist=30.0)
        ref = renderer.render_isosurface(v, 0.0, cam, culling="none", cull_depth=md - 2)
        # occluders coarser, as coarse as, and finer than the tested nodes
        for od, cd in ((md - 1, md - 2), (md - 2, md - 3), (md - 2, md - 1), (md - 1, md - 1), (md, md - 1)):
            res = renderer.render_isosurface(v, 0.0, cam, occluder_depth=od, cull_depth=cd)
            assert np.array_equal(res.image, ref.image), (az, od, cd)
            assert res.stats["surface_triangles"] <= ref.stats["surface_triangles"]
        # Fine occluders cull a good part of this (heavily aliased) surface.
        assert res.stats["surface_triangles"] < 0.9 * ref.stats["surface_triangles"]


def test_renderresult_fields(renderer):
    v = sphere_volume(16, 0.5)
    cam, _ = cam_around(10)
    res = renderer.render_isosurface(v, 0.0, cam)
    assert res.image.shape == (H, W, 4) and res.image.dtype == np.uint8
    assert res.depth.shape == (H, W) and res.depth.dtype == np.float32
    n = res.stats["nodes_straddling"]
    assert res.tile_pixels.shape == (n,) and res.tile_drawn.shape == (n,) and res.nodes.shape == (n, 4)
    for k in ("surface_triangles", "nodes_tested", "nodes_visible", "occluder_ms", "cull_ms", "surface_ms", "total_ms"):
        assert k in res.stats
    assert "RenderResult" in repr(res)


def test_float64_values_keep_their_precision_about_a_large_mean(renderer):
    # A sphere-like field of 0 +- 1, and the same field plus 1e8: float32 alone holds every sample
    # of the second as 1e8, so without the value offset its isosurface at 1e8 is empty.
    z, y, x, h = grid(24)
    base = np.sqrt(x * x + y * y + z * z) - 0.6  # float64, in [-0.6, 1.1]
    cam, _ = cam_around(40)
    small = gc.Volume(base, origin=(-1, -1, -1), spacing=(h, h, h))
    big = gc.Volume(base + 1e8, origin=(-1, -1, -1), spacing=(h, h, h))
    assert abs(big.offset - 1e8) < 1.0 and big.nodes(0)["max"][0] == pytest.approx(1e8 + base.max(), abs=1e-6)
    for culling in ("none", "implicit"):
        a = renderer.render_isosurface(small, 0.0, cam, culling=culling)
        b = renderer.render_isosurface(big, 1e8, cam, culling=culling)
        assert a.stats["surface_triangles"] > 0
        assert b.stats["surface_triangles"] == a.stats["surface_triangles"]
        np.testing.assert_array_equal(a.image, b.image)
    # integers too: 1e8 and 1e8 + 1 differ (a volume at the default origin and spacing, seen from
    # outside: the camera above sits inside it, looking away from its surface)
    ints = gc.Volume((base > 0).astype(np.int64) + 10**8)
    cam_i, _ = cam_around(40, dist=60.0, center=(11.5, 11.5, 11.5))
    ref = renderer.render_isosurface(ints, 1e8 + 0.5, cam_i, culling="none")
    res = renderer.render_isosurface(ints, 1e8 + 0.5, cam_i)
    assert 0 < res.stats["surface_triangles"] < ref.stats["surface_triangles"]
    np.testing.assert_array_equal(res.image, ref.image)
    with pytest.raises(gc.InputError, match="^isovalue"):
        renderer.render_isosurface(big, 1e300, cam)


def contour_bricks(vals, w, b=4):
    """The walk's contour bricks by their definition: (bricks of b^3 cells, those holding a cell
    whose corners are not all on one side of w)."""
    a = vals >= w
    cz, cy, cx = (n - 1 for n in vals.shape)
    same = np.ones((cz, cy, cx), bool)
    for dz in (0, 1):
        for dy in (0, 1):
            for dx in (0, 1):
                same &= a[dz:dz + cz, dy:dy + cy, dx:dx + cx] == a[:-1, :-1, :-1]
    bz, by, bx = (-(-n // b) for n in (cz, cy, cx))
    passable = np.zeros((bz * b, by * b, bx * b), bool)
    passable[:cz, :cy, :cx] = ~same
    return bz * by * bx, int(passable.reshape(bz, b, by, b, bx, b).any(axis=(1, 3, 5)).sum())


@pytest.mark.parametrize("walk", WALKS)
def test_contour_bricks_kept_where_the_walk_runs(walk):
    # The walk places the contour of the faces it crosses from the samples of the bricks of 4^3
    # cells that hold surface (a word per brick, 125 samples per brick with surface), kept with
    # the class grid: made by the first implicit frame with single-cell occluders, dropped with
    # the caches; by default for the compute walk only where at least half the bricks hold surface
    # (a wavy field, not a small sphere), always for the host's; coarser occluders and "none" make
    # none.
    r = gc.Renderer(48, 40)
    cam, _ = cam_around(30.0)
    z, y, x, h = grid(24)
    wavy = (np.sin(7 * x) + np.cos(6 * y + 2 * x) + 0.8 * np.sin(9 * z) - 0.2).astype(np.float32)
    small = (np.sqrt(x * x + y * y + z * z) - 0.3).astype(np.float32)
    for vals, dense in [(wavy, True), (small, False)]:
        v = gc.Volume(vals, origin=(-1, -1, -1), spacing=(h, h, h))
        bricks, stored = contour_bricks(vals, 0.0)
        assert (stored >= bricks / 2) == dense, (stored, bricks)
        # (the host's walk places contours wherever the surface is)
        expected = 4 * (bricks + 125 * stored) if dense or walk == "cpu" else 0
        md = v.max_depth()
        assert r.render_isosurface(v, 0.0, cam, culling="none").stats["contour_bytes"] == 0
        assert r.render_isosurface(v, 0.0, cam, occluder_depth=md - 1, walk=walk).stats["contour_bytes"] == 0
        assert r.render_isosurface(v, 0.0, cam, walk=walk).stats["contour_bytes"] == expected
        assert r.render_isosurface(v, 0.0, cam, culling="none").stats["contour_bytes"] == expected
        gc.iso.clear_cache(r)
        assert r.render_isosurface(v, 0.0, cam, culling="none").stats["contour_bytes"] == 0


def test_patches_kept_on_the_gpu_draw_what_a_fresh_upload_draws():
    # Cached patches stay on the GPU between frames (appended as views reveal them); frames drawn
    # from there equal frames uploaded from scratch (cache=False), across views, both cullings,
    # and a change of exaggeration (a new render space: the GPU copy starts again). Uncached
    # implicit frames extract only the cells the walk saw: the same triangles, fewer vertices.
    r = gc.Renderer(56, 48)
    v = sphere_volume(40, 0.6)
    sizes, vertices = [], []
    for az, zs in [(0, 1.0), (120, 1.0), (240, 1.0), (60, 2.5), (0, 1.0)]:
        a, e = np.radians(az), np.radians(25.0)
        cam = gc.Camera.look_at(4 * np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)]), (0, 0, 0),
                                up=(0, 0, 1), fov_y=40.0, z_scale=zs)
        for culling in ("implicit", "none"):
            kept = r.render_isosurface(v, 0.1, cam, culling=culling)
            fresh = r.render_isosurface(v, 0.1, cam, culling=culling, cache=False)
            assert kept.stats["surface_triangles"] == fresh.stats["surface_triangles"] > 0
            np.testing.assert_array_equal(kept.image, fresh.image)
            np.testing.assert_array_equal(kept.depth, fresh.depth)
            sizes.append(kept.stats["gpu_cache_bytes"])
            if culling == "implicit":
                vertices.append((fresh.stats["surface_vertices"], kept.stats["surface_vertices"]))
    assert min(sizes) > 0
    assert all(f < k for f, k in vertices), vertices
    gc.iso.clear_cache(r)
    assert r.render_isosurface(v, 0.1, cam, cache=False).stats["gpu_cache_bytes"] == 0


def test_patch_cache_is_bounded_by_its_budget():
    r = gc.Renderer(48, 48)
    v = sphere_volume(40, 0.6)
    cam, _ = cam_around(30)
    assert gc.iso.cache_budget(r) == r.iso_cache_budget == 256 * 2**20
    a = r.render_isosurface(v, 0.3, cam)  # the largest surface of those below
    one = a.stats["cache_bytes"]
    assert one > 0
    budget = int(2.5 * one)
    gc.iso.set_cache_budget(r, budget)
    sizes = []
    for w in np.linspace(-0.3, 0.3, 12):
        res = r.render_isosurface(v, float(w), cam)
        sizes.append(res.stats["cache_bytes"])
        assert res.stats["cache_bytes"] <= budget
        # the GPU copy of the cached patches (no f64 positions) stays within ~2 x theirs
        assert 0 < res.stats["gpu_cache_bytes"] <= 2 * budget
        # evictions never change what is drawn
        np.testing.assert_array_equal(res.image, r.render_isosurface(v, float(w), cam, cache=False).image)
    assert max(sizes) > one  # it does keep more than one isovalue's patches
    # the most recently used isovalue is still cached; a raised budget keeps everything again
    assert r.render_isosurface(v, 0.3, cam).stats["patches_extracted"] == 0
    r.iso_cache_budget = 2**40
    for w in (0.05, 0.1, 0.05):
        last = r.render_isosurface(v, w, cam)
    assert last.stats["patches_extracted"] == 0
    gc.iso.set_cache_budget(r, 0)  # nothing is kept
    none_kept = r.render_isosurface(v, 0.0, cam).stats
    assert none_kept["cache_bytes"] == none_kept["gpu_cache_bytes"] == 0
    with pytest.raises(gc.InputError, match="^bytes"):
        gc.iso.set_cache_budget(r, -1)
    with pytest.raises(gc.InputError, match="^bytes"):
        gc.iso.set_cache_budget(r, 1.5)


# ---- NaN: outside the domain, never an occluder, never crossed by a proof


def nan_slab_volume(n=40):
    """Above (x > 0.7) | NaN slab (0.6 <= x <= 0.7) | Below, holding a blob (a ball where the
    field is above) near x = 0.2: seen from +x, the Above and Below regions pair up across the slab,
    but no surface lies between them (NaN cells have none), so the blob is visible."""
    z, y, x, h = grid(n, 0.0, 1.0)
    blob = np.sqrt((x - 0.2) ** 2 + (y - 0.5) ** 2 + (z - 0.5) ** 2) < 0.15
    vals = np.where(x > 0.7, 1.0, np.where(blob, 1.0, -1.0)) + 0 * (y + z)
    vals = np.where((x >= 0.6) & (x <= 0.7), np.nan, vals).astype(np.float32)
    return gc.Volume(vals, spacing=(h, h, h))


@pytest.mark.parametrize("walk", WALKS)
def test_nan_slab_does_not_hide_what_none_shows(renderer, walk):
    v = nan_slab_volume()
    md = v.max_depth()
    cam = gc.Camera.look_at((4.0, 0.5, 0.5), (0.0, 0.5, 0.5), up=(0, 0, 1), fov_y=30.0)
    ref = renderer.render_isosurface(v, 0.0, cam, culling="none")
    assert np.isfinite(ref.depth).sum() > 100  # the blob is seen
    for od, cd in ((md, md - 1), (md - 1, md - 2), (md - 2, md - 3)):
        res = renderer.render_isosurface(v, 0.0, cam, occluder_depth=od, cull_depth=cd, return_map=True, walk=walk)
        np.testing.assert_array_equal(res.image, ref.image)
        assert res.stats["occluder_nodes_nan"] > 0 and res.stats["occluder_boxes_above"] > 0
        # nothing is proven through the slab: where the map holds, it lies behind the blob's surface
        # (a Below node then an Above node inside the blob)
        m = res.occlusion_map
        proven = np.isfinite(m)
        assert np.isfinite(ref.depth[proven]).all()
        assert (ref.depth[proven] <= m[proven] * (1 + 1e-5)).all()


def test_nodes_with_nan_are_not_occluders():
    vals = np.ones((9, 9, 9), np.float32)
    vals[4, 4, 4] = np.nan
    v = gc.Volume(vals)
    # depth 1: 8 nodes of 4^3 cells; those touching sample (4, 4, 4) are all of them
    nodes = v.nodes(1)
    assert (nodes["min"] == 1.0).all()
    r = gc.Renderer(32, 32)
    res = r.render_isosurface(v, 0.0, gc.Camera.look_at((20, 15, 10), (4, 4, 4)), occluder_depth=1, cull_depth=1)
    assert res.stats["occluder_boxes_above"] == 0 and res.stats["occluder_nodes_nan"] == 8


@pytest.mark.parametrize("walk", WALKS)
@pytest.mark.parametrize("border", [1, 3])
def test_nan_borders_implicit_equals_none(renderer, border, walk):
    vals, origin, spacing = data.pesco_synthetic(40)
    vals = vals.copy()
    for ax in range(3):
        sl = [slice(None)] * 3
        sl[ax] = slice(0, border)
        vals[tuple(sl)] = np.nan
        sl[ax] = slice(-border, None)
        vals[tuple(sl)] = np.nan
    v = gc.Volume(vals, origin=origin, spacing=spacing)
    md = v.max_depth()
    for az in (20.0, 200.0):
        cam, _ = cam_around(az, 25.0, dist=30.0)
        ref = renderer.render_isosurface(v, 0.0, cam, culling="none")
        for od, cd in ((md - 1, md - 2), (md, md - 1)):
            res = renderer.render_isosurface(v, 0.0, cam, occluder_depth=od, cull_depth=cd, walk=walk)
            np.testing.assert_array_equal(res.image, ref.image)
        # the border stops no proof inside: the hidden part is still culled
        assert res.stats["surface_triangles"] < 0.9 * ref.stats["surface_triangles"]
    # no triangle through a NaN cell: every vertex lies inside the finite core
    verts, _ = gc.extract_isosurface(v, 0.0)
    lo = np.array(origin) + border * np.array(spacing)
    hi = np.array(origin) + (39 - border) * np.array(spacing)
    assert (verts >= lo - 1e-9).all() and (verts <= hi + 1e-9).all()


def bricky_volume():
    """Wholly below under a plane, wholly above over it (the walk's skip bricks of 4³ and 16³ cells),
    a NaN slab, and small blobs of the other class centred on brick corners, edges and faces."""
    z, y, x = np.meshgrid(np.arange(40.0), np.arange(36.0), np.arange(48.0), indexing="ij")
    base = np.where(z > 20.5, 1.0, -1.0)
    blobs = ((16, 16, 16), (32, 20, 12), (4, 30.5, 8), (16, 16, 32), (33.5, 8, 28), (44, 32, 24.5))
    bump = sum(np.exp(-((x - bx) ** 2 + (y - by) ** 2 + (z - bz) ** 2) / 2.0) for bx, by, bz in blobs)
    vals = (base * (1.0 - 2.5 * bump)).astype(np.float32)
    vals[:18, :, 40:44] = np.nan
    return gc.Volume(vals, origin=(0.0, 0.0, 0.0), spacing=(1.0, 1.0, 1.0))


@pytest.mark.parametrize("walk", WALKS)
@pytest.mark.parametrize("projection", ["perspective", "orthographic"])
def test_space_skipping_keeps_implicit_equal_to_none(renderer, projection, walk):
    v = bricky_volume()
    md = v.max_depth()
    c = (23.5, 17.5, 19.5)
    views = [(c[0] + 70, c[1] + 50, c[2] + 40), (c[0] - 40, c[1] + 10, c[2] - 50), (c[0] + 0.5, c[1], c[2] + 90)]
    culled = 0
    for eye in views:
        cam = gc.Camera.look_at(eye, c, up=(0, 1, 0.3), fov_y=45.0, projection=projection, ortho_height=60.0)
        ref = renderer.render_isosurface(v, 0.0, cam, culling="none")
        for cd in (None, md, md - 3):
            res = renderer.render_isosurface(v, 0.0, cam, cull_depth=cd, walk=walk)
            np.testing.assert_array_equal(res.image, ref.image)
            np.testing.assert_array_equal(res.depth, ref.depth)
            culled += res.stats["surface_triangles"] < ref.stats["surface_triangles"]
    assert culled >= 6


# ---- Marching cubes: closed, on the isovalue, VTK's triangle count


def edge_use(faces):
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    return counts


def test_extract_isosurface_is_watertight_on_closed_fields():
    rng = np.random.default_rng(3)
    vals = rng.uniform(-1, 1, (18, 17, 16)).astype(np.float32)  # ambiguous faces everywhere
    vals[[0, -1], :, :] = vals[:, [0, -1], :] = vals[:, :, [0, -1]] = 1.0
    for v in (sphere_volume(30, 0.6), gc.Volume(vals, spacing=(0.5, 1.0, 2.0))):
        verts, faces = gc.extract_isosurface(v, 0.0)
        assert len(faces) > 0
        assert (edge_use(faces) == 2).all()


@pytest.mark.parametrize("n", [32, 48])
def test_triangle_count_matches_vtk_flying_edges(n):
    pv = pytest.importorskip("pyvista")
    vals, origin, spacing = data.pesco_synthetic(n)
    g = pv.ImageData(dimensions=vals.shape[::-1], origin=origin, spacing=spacing)
    g.point_data["f"] = vals.ravel()
    vtk_count = g.contour([0.0], scalars="f", method="flying_edges").n_cells
    verts, faces = gc.extract_isosurface(gc.Volume(vals, origin=origin, spacing=spacing), 0.0)
    assert abs(len(faces) / vtk_count - 1.0) < 0.02, (len(faces), vtk_count)
    # the vertices lie on the isovalue: trilinear interpolation of the samples there is ~0
    from scipy.ndimage import map_coordinates

    g = (verts - np.array(origin)) / np.array(spacing)
    # edge vertices (two grid coordinates integral); the rare loop centroids are not on the surface
    on_edge = (np.abs(g - np.round(g)) < 1e-6).sum(axis=1) >= 2
    assert on_edge.mean() > 0.99
    f = map_coordinates(vals.astype(np.float64), g[on_edge][:, ::-1].T, order=1)  # (k, j, i)
    assert np.abs(f).max() < 1e-5


def test_setup_is_reported_apart_from_the_frame():
    r = gc.Renderer(40, 40)
    v = sphere_volume(16, 0.5)
    cam, _ = cam_around(30)
    a = r.render_isosurface(v, 0.0, cam)
    b = r.render_isosurface(v, 0.0, cam)
    assert a.stats["setup_ms"] > 0 and b.stats["setup_ms"] == 0
    # one submission and one read-back for the compute walk (none for the host's), one for the draw
    s = r.render_isosurface(v, 0.0, cam, walk="gpu").stats
    assert s["readbacks"] == 1 and s["submissions"] == 2
    assert r.render_isosurface(v, 0.0, cam, culling="none").stats["readbacks"] == 0


@pytest.mark.parametrize("projection", ["perspective", "orthographic"])
def test_oracle_draws_fewest_cells_and_the_same_image(renderer, projection):
    """culling="oracle" on a rotated survey grid with vertical exaggeration and a NaN border (the
    pixel rays turned and scaled as the frame's): none's image, fewer triangles than implicit."""
    z, y, x, h = grid(28)
    vals = (np.sin(3 * x) * np.cos(2 * y) + 0.8 * z).astype(np.float32)
    vals[:, :, :2] = np.nan
    v = gc.Volume(vals, origin=(431000.0, 6780000.0, -1.0), spacing=(h, h, h), rotation=30.0)
    c = np.array([431000.0, 6780000.0, 0.0])
    cam = gc.Camera.look_at(c + (3.0, -2.0, 2.5), c, up=(0, 0, 1), fov_y=40.0, projection=projection,
                            ortho_height=3.0, z_scale=2.0)
    ref = renderer.render_isosurface(v, 0.0, cam, culling="none")
    imp = renderer.render_isosurface(v, 0.0, cam, culling="implicit")
    orc = renderer.render_isosurface(v, 0.0, cam, culling="oracle")
    np.testing.assert_array_equal(orc.image, ref.image)
    np.testing.assert_array_equal(orc.depth, ref.depth)
    assert (ref.depth < np.inf).mean() > 0.2
    assert 0 < orc.stats["surface_triangles"] < imp.stats["surface_triangles"] < ref.stats["surface_triangles"]
    assert orc.stats["cull_ms"] == 0.0 and orc.stats["readbacks"] == 0


# ---- Random volumes: the walk's cell and face occluders never cull a visible triangle

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, example, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

# GEOCULL_ISO_EXAMPLES (default 60) random cases; GEOCULL_FUZZ_RANDOM=1 draws new ones.
ISO_EXAMPLES = int(os.environ.get("GEOCULL_ISO_EXAMPLES", "60"))
CULLED: list[int] = []


@settings(max_examples=ISO_EXAMPLES, deadline=None, derandomize=not os.environ.get("GEOCULL_FUZZ_RANDOM"),
          database=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), shape=st.tuples(*[st.integers(6, 14)] * 3), smooth=st.sampled_from([0, 1, 3]),
       nan=st.sampled_from([0.0, 0.02, 0.2]), on_iso=st.sampled_from([0.0, 0.1]), elev=st.floats(-85.0, 85.0),
       az=st.floats(0.0, 360.0), dist=st.floats(0.3, 4.0), ortho=st.booleans())
# A ray 0.0003 cells inside a face bordering NaN cells crossed the surface next to its boundary
# edge, where the rasteriser put the pixel beyond the edge: the walk's proofs keep a cell away
# from NaN (bricks::dilate_nan).
@example(seed=14, shape=(14, 11, 14), smooth=3, nan=0.02, on_iso=0.0, elev=0.0, az=0.0, dist=2.265625, ortho=False)
# An axis-aligned orthographic view whose pixel row runs along the box's top face: the walk took
# the ray's zero z direction for a tiny upward one and left the box at its first cell.
@example(seed=0, shape=(13, 6, 10), smooth=0, nan=0.0, on_iso=0.0, elev=0.0, az=0.0, dist=1.0, ortho=True)
def _random_volume_renders_as_none(seed, shape, smooth, nan, on_iso, elev, az, dist, ortho):
    """Noise (thin sheets, ambiguous faces), smoothed noise (blobs), NaN samples and samples on the
    isovalue itself; cameras outside, at the border and inside: implicit's image equals none's, and
    so does the oracle's (its cells read back from none's depth). The one known failure
    (:data:`KNOWN_ISO_MISS`) is tested on its own, strictly expected to fail until it is fixed."""
    if (seed, shape, smooth, elev, az, dist, ortho) == KNOWN_ISO_MISS:
        return
    _render_as_none(seed, shape, smooth, nan, on_iso, elev, az, dist, ortho)


# Found 2026-12-06 (full runs of the suite reached it; isolated runs of this file did not): both
# walks leave out one pixel's surface (pixel (24, 27): the triangle of cell (9, 10, 0) that touches
# the cell's y = 11 and z = 0 faces, 0.0002 of a cell from y = 11 and 0.006 above the volume's
# bottom face, at a 3° grazing view); the build before that day's changes does the same.
KNOWN_ISO_MISS = (9, (13, 13, 13), 1, 3.0, 3.0, 3.0, False)


@pytest.mark.xfail(strict=True, reason="known implicit-walk miss at a grazing ray by the box's bottom face")
def test_known_grazing_miss_at_the_bottom_face():
    seed, shape, smooth, elev, az, dist, ortho = KNOWN_ISO_MISS
    _render_as_none(seed, shape, smooth, 0.0, 0.0, elev, az, dist, ortho)


def _render_as_none(seed, shape, smooth, nan, on_iso, elev, az, dist, ortho):
    rng = np.random.default_rng(seed)
    vals = rng.normal(size=shape[::-1])
    for _ in range(smooth):
        vals = (vals + np.roll(vals, 1, 0) + np.roll(vals, 1, 1) + np.roll(vals, 1, 2)) / 4
    vals = np.sign(vals) * np.abs(vals) ** 0.5
    vals[rng.random(vals.shape) < on_iso] = 0.0
    vals[rng.random(vals.shape) < nan] = np.nan
    v = gc.Volume(vals.astype(np.float32), origin=(0, 0, 0), spacing=(1, 1, 1))
    size = np.array(shape, dtype=float) - 1
    c = size / 2
    e, a = np.radians(elev), np.radians(az)
    eye = c + dist * np.linalg.norm(size) * np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    cam = gc.Camera.look_at(tuple(eye), tuple(c), up=(0, 0, 1), fov_y=50.0,
                            projection="orthographic" if ortho else "perspective", ortho_height=float(size.max()) * 1.2)
    r = gc.Renderer(48, 40)
    ref = r.render_isosurface(v, 0.0, cam, culling="none")
    for walk in WALKS:
        res = r.render_isosurface(v, 0.0, cam, walk=walk)
        np.testing.assert_array_equal(res.image, ref.image)
        np.testing.assert_array_equal(res.depth, ref.depth)
    orc = r.render_isosurface(v, 0.0, cam, culling="oracle")
    np.testing.assert_array_equal(orc.image, ref.image)
    CULLED.append(ref.stats["surface_triangles"] - res.stats["surface_triangles"])


def test_random_volumes_and_cameras_render_as_none():
    CULLED.clear()
    _random_volume_renders_as_none()
    assert sum(k > 0 for k in CULLED) >= ISO_EXAMPLES // 3, CULLED
