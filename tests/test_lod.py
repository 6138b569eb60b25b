"""lod="screen_error": each drawn tile at the coarsest level whose error projects to at most
max_pixel_error pixels at its nearest point; levels keep their tile's border, so tiles at
different levels meet without cracks."""

from __future__ import annotations

import math

import numpy as np
import pytest

import geocull as gc

SPACING = 10.0


def wavy(n: int = 65, amp: float = 20.0, tiles: int = 4) -> gc.Scene:
    """A smooth n x n height field (x, y in [0, (n-1) * SPACING]) of tiles x tiles tiles."""
    x = np.arange(n) * SPACING
    z = amp * np.sin(x[None, :] / 90.0) * np.cos(x[:, None] / 70.0)
    s = gc.Scene()
    s.add_heightfield(z, origin=(0.0, 0.0), spacing=(SPACING, SPACING), tiles=(tiles, tiles))
    return s


def nearest_distance(box_min, box_max, eye) -> float:
    q = np.clip(eye, box_min, box_max)
    return float(np.linalg.norm(q - eye))


def test_levels_exist_and_shrink():
    t = wavy().tile_table()
    assert (t["level_triangles"][:, 0] == t["tris_fine"]).all()
    assert (t["level_error"][:, 0] == 0).all()
    for row in t:
        n = row["level_triangles"][row["level_triangles"] > 0]
        # Each level quarters the one before until its full-resolution border dominates; the
        # levels past that exist for groups of tiles (lod::groups), whose shared sides are coarse.
        assert len(n) >= 3 and (n[1:3] <= 0.6 * n[:2]).all() and (n[1:] < n[:-1]).all(), n
        e = row["level_error"][: len(n)]
        assert np.isfinite(e).all() and (e[1:] > 0).all()


@pytest.mark.parametrize("bound", [0.5, 2.0, 8.0])
def test_chosen_level_respects_the_bound_at_hand_computed_distances(renderer_small, bound):
    s = wavy()
    r = renderer_small(160, 120)
    eye = np.array([-200.0, -300.0, 400.0])
    cam = gc.Camera.look_at(eye, (320.0, 320.0, 0.0), fov_y=40.0)
    res = r.render(s, cam, lod="screen_error", max_pixel_error=bound)
    assert res.tile_level is not None and res.tile_error_px is not None
    t = s.tile_table()
    f_px = 120 / 2 / math.tan(math.radians(40.0) / 2)  # pixels per unit at unit distance
    regrouped = 0
    for i, row in enumerate(t):
        d = nearest_distance(row["bbox_min"], row["bbox_max"], eye)
        px = row["level_error"] * f_px / d
        ok = [lv for lv in range(6) if np.isfinite(px[lv]) and (px[: lv + 1] <= bound).all()]
        expected = max(ok)
        # Every tile takes the coarsest level within the bound, with its level's error, or the
        # group error (at least its level's) where it draws sides shared coarse with neighbours
        # at that level (lod::groups, which never changes a level).
        level, err = int(res.tile_level[i]), float(res.tile_error_px[i])
        assert level == expected, (i, level, expected, px)
        assert err >= px[level] * (1 - 1e-4) - 1e-6 and err <= bound, (i, err, px)
        if err != pytest.approx(px[level], rel=1e-4, abs=1e-6):
            regrouped += 1
    assert regrouped <= res.stats["tiles_grouped"], regrouped
    assert res.stats["lod_max_error_px"] <= bound


def test_close_camera_gets_level_zero(renderer_small):
    s = wavy()
    r = renderer_small(64, 48)
    cam = gc.Camera.look_at((100.0, 100.0, 30.0), (150.0, 150.0, 0.0))
    res = r.render(s, cam, lod="screen_error", max_pixel_error=0.5)
    t = s.tile_table()
    near = (t["ix"] == 0) & (t["iy"] == 0)
    assert res.tile_level[near][0] == 0


def assert_no_cracks(full: gc.RenderResult, lod: gc.RenderResult) -> None:
    """Every pixel the full-resolution image covers is covered in the lod one, except next to the
    full image's own silhouette (where a coarser ridge may move by up to the bound)."""
    empty = ~full.coverage
    near_silhouette = empty.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            near_silhouette |= np.roll(np.roll(empty, dy, axis=0), dx, axis=1)
    cracks = full.coverage & ~lod.coverage & ~near_silhouette
    assert not cracks.any(), np.argwhere(cracks)[:10]


@pytest.mark.parametrize("culling", ["none", "three_pass", "frustum"])
def test_no_cracks_between_tiles_at_different_levels(renderer_small, culling):
    """A grazing view over the field: near tiles fine, far ones coarse. No background pixel opens
    inside the surface: every pixel the full-resolution image covers is covered, except on the
    full image's own silhouette (where a coarser ridge may move by up to the bound)."""
    s = wavy(amp=20.0)
    r = renderer_small(200, 150)
    cam = gc.Camera.look_at((-60.0, -60.0, 40.0), (400.0, 400.0, 0.0), fov_y=50.0)
    full = r.render(s, cam, culling=culling, pixel_threshold=0)
    lod = r.render(s, cam, culling=culling, pixel_threshold=0, lod="screen_error", max_pixel_error=0.5)
    levels = set(lod.tile_level[lod.tile_drawn].tolist())
    assert len(levels) >= 3, levels  # the test needs neighbours at different levels
    assert_no_cracks(full, lod)
    assert (full.coverage != lod.coverage).mean() < 0.001
    assert lod.stats["triangles_drawn"] < full.stats["triangles_drawn"]


@pytest.mark.parametrize("culling", ["none", "temporal"])
def test_tiles_drawn_in_groups_leave_no_cracks_and_save_triangles(renderer_small, culling):
    """Neighbouring tiles at one level draw the sides they share at that level's stride
    (lod::groups): the grazing view above over 8 x 8 tiles stitches dozens of them, no background
    pixel opens inside the surface, and the frame draws fewer triangles than the same levels
    with every border at full resolution (the tile table's level_triangles)."""
    s = wavy(n=257, tiles=8)
    r = renderer_small(200, 150)
    cam = gc.Camera.look_at((-60.0, -60.0, 40.0), (400.0, 400.0, 0.0), fov_y=50.0)
    full = r.render(s, cam, culling=culling, pixel_threshold=0)
    lod = r.render(s, cam, culling=culling, pixel_threshold=0, lod="screen_error", max_pixel_error=0.5)
    if culling == "temporal":
        lod = r.render(s, cam, culling=culling, pixel_threshold=0, lod="screen_error", max_pixel_error=0.5)
    assert lod.stats["tiles_grouped"] >= 16, lod.stats["tiles_grouped"]
    assert_no_cracks(full, lod)
    t = s.tile_table()
    drawn = lod.tile_drawn
    bordered = int(t["level_triangles"][np.arange(len(t)), lod.tile_level][drawn].sum())
    assert lod.stats["triangles_drawn"] < 0.9 * bordered, (lod.stats["triangles_drawn"], bordered)


def test_image_equals_full_within_the_bound(renderer_small):
    """Differing pixels measured, not assumed: with 0.5 px the depth moves by less than the bound
    allows, and since a height field shades and colours by z from its fine surface whatever level
    is drawn, colours differ only where a pixel's surface point moves (sub-pixel): by at most a
    few levels (facet shading of the coarser levels gave 0.5 % beyond 8/255 here)."""
    s = wavy()
    r = renderer_small(160, 120)
    cam = gc.Camera.look_at((-300.0, -400.0, 500.0), (320.0, 320.0, 0.0))
    full = r.render(s, cam)
    lod = r.render(s, cam, lod="screen_error", max_pixel_error=0.5)
    assert lod.stats["triangles_drawn"] < 0.6 * full.stats["triangles_drawn"]
    np.testing.assert_array_equal(lod.coverage, full.coverage)
    diff = np.abs(lod.image.astype(int) - full.image.astype(int)).max(axis=2)
    assert (diff > 4).mean() < 0.001, (diff > 4).mean()
    assert (diff > 2).mean() < 0.01, (diff > 2).mean()
    cov = full.coverage
    rel = np.abs(lod.depth[cov] - full.depth[cov]) / full.depth[cov]
    assert np.median(rel) < 1e-3


def test_bad_lod_arguments(renderer_small):
    s, r = wavy(), renderer_small(16, 16)
    cam = gc.Camera.look_at((0.0, 0.0, 100.0), (300.0, 300.0, 0.0))
    with pytest.raises(gc.InputError, match="^lod"):
        r.render(s, cam, lod="fast")  # type: ignore[arg-type]
    with pytest.raises(gc.InputError, match="^max_pixel_error"):
        r.render(s, cam, lod="screen_error", max_pixel_error=0)


def test_levels_survive_pickling_and_copies(renderer_small):
    import copy
    import pickle

    s = wavy()
    r = renderer_small(96, 72)
    cam = gc.Camera.look_at((-200.0, -300.0, 400.0), (320.0, 320.0, 0.0))
    ref = r.render(s, cam, lod="screen_error", max_pixel_error=2.0)
    for other in (pickle.loads(pickle.dumps(s)), copy.deepcopy(s)):
        np.testing.assert_array_equal(other.tile_table()["level_error"], s.tile_table()["level_error"])
        res = r.render(other, cam, lod="screen_error", max_pixel_error=2.0)
        np.testing.assert_array_equal(res.image, ref.image)
        np.testing.assert_array_equal(res.tile_level, ref.tile_level)


def lod_against_full(r: gc.Renderer, s: gc.Scene, cam: gc.Camera) -> np.ndarray:
    """Per pixel, the largest channel difference between lod="screen_error" at 0.5 px and the fine
    image, after checking that the coarser levels were really drawn."""
    full = r.render(s, cam)
    lod = r.render(s, cam, lod="screen_error", max_pixel_error=0.5)
    assert lod.stats["triangles_drawn"] < 0.6 * full.stats["triangles_drawn"]
    return np.abs(lod.image.astype(int) - full.image.astype(int)).max(axis=2)


@pytest.mark.parametrize("rotation", [0.0, 33.0])
def test_coarse_levels_shade_as_the_fine_surface(renderer_small, rotation):
    """A flat-coloured height field drawn at coarse levels shades like level 0: the normal comes
    from the fine surface's gradients at the pixel's (x, y), rotated grids included."""
    x = np.arange(65) * SPACING
    z = 20.0 * np.sin(x[None, :] / 90.0) * np.cos(x[:, None] / 70.0)
    s = gc.Scene()
    s.add_heightfield(z, origin=(450000.0, 6780000.0), spacing=(SPACING, SPACING), tiles=(4, 4),
                      color=(0.7, 0.6, 0.4), rotation=rotation)
    r = renderer_small(160, 120)
    cam = gc.Camera.fit(s, azimuth=200.0, elevation=35.0, aspect=160 / 120)
    diff = lod_against_full(r, s, cam)
    assert (diff > 2).mean() < 0.002, (diff > 2).mean()


def curved_sheet(n: int = 120) -> tuple[np.ndarray, np.ndarray]:
    """A steep, gently curved fault-like sheet (n x n vertices, 400 m a side)."""
    u, v = np.meshgrid(np.linspace(0.0, 400.0, n), np.linspace(0.0, 400.0, n))
    x = u + 30.0 * np.sin(v / 80.0)
    y = 0.35 * v
    z = -0.94 * v + 20.0 * np.cos(u / 60.0)
    verts = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    k = np.arange(n * n).reshape(n, n)[:-1, :-1].ravel()
    faces = np.concatenate([np.stack([k, k + 1, k + n + 1], 1), np.stack([k, k + n + 1, k + n], 1)])
    return verts, faces


@pytest.mark.parametrize("structured", [True, False])
def test_a_curved_fault_matches_full_resolution(renderer_small, structured):
    """A mesh's level is taken only if its shading error (how far its normals there turn from
    level 0's) changes the lit colour by at most half an 8-bit level: a curved fault at lod=0.5
    differs from lod="full" by at most one level, in few pixels (before, its coarser levels shifted
    11 % of the pixels here by up to two levels); the levels within the bound are still drawn. A
    structured grid (faces as grid_faces) shades every level from its fine grid's normals, so its
    levels turn the normals far less than the same sheet triangulated otherwise, whose levels
    interpolate their vertices' normals."""
    v, f = curved_sheet()
    if not structured:  # the other diagonal of every cell: not a grid the renderer recognises
        n = 120
        k = np.arange(n * n).reshape(n, n)[:-1, :-1].ravel()
        f = np.concatenate([np.stack([k, k + 1, k + n], 1), np.stack([k + 1, k + n + 1, k + n], 1)])
    s = gc.Scene()
    color = (0.8, 0.5, 0.4)
    s.add_mesh(v, f, kind="fault", tiles=8, color=color)
    r = renderer_small(160, 120)
    cam = gc.Camera.fit(s, azimuth=160.0, elevation=25.0, aspect=160 / 120)
    full = r.render(s, cam)
    lod = r.render(s, cam, lod="screen_error", max_pixel_error=0.5)
    t = s.tile_table()
    shading = t["level_shading_error"]
    assert (shading[:, 1:3] > 0).all()
    # in 8-bit levels: level 1 of the grid within the bound everywhere, of the other sheet not
    levels1 = shading[:, 1] * 255 * max(color) * 0.8
    assert (levels1 < 0.5).all() if structured else (levels1 > 0.1).all(), levels1
    chosen = shading[np.arange(len(t)), lod.tile_level]
    assert (chosen * 255 * max(color) * 0.8 <= 0.5 + 1e-6).all(), chosen
    assert lod.stats["triangles_drawn"] < full.stats["triangles_drawn"]  # some coarser levels pass
    np.testing.assert_array_equal(lod.coverage, full.coverage)
    diff = np.abs(lod.image.astype(int) - full.image.astype(int)).max(axis=2)
    assert diff.max() <= 1, diff.max()
    assert (diff > 0).mean() < 0.01, (diff > 0).mean()


def test_a_flat_fault_keeps_its_coarse_levels(renderer_small):
    """A planar mesh's levels have no shading error: they are drawn, and shade as level 0."""
    n = 120
    u, w = np.meshgrid(np.linspace(0.0, 400.0, n), np.linspace(0.0, 400.0, n))
    v = np.stack([u, 0.35 * w, -0.94 * w], axis=-1).reshape(-1, 3)
    s = gc.Scene()
    s.add_mesh(v, gc.data.grid_faces(n, n), kind="fault", tiles=8, color=(0.8, 0.5, 0.4))
    assert np.nanmax(s.tile_table()["level_shading_error"]) < 1e-4
    r = renderer_small(160, 120)
    cam = gc.Camera.fit(s, azimuth=160.0, elevation=25.0, aspect=160 / 120)
    diff = lod_against_full(r, s, cam)
    assert (diff > 0).mean() < 0.001, (diff > 0).mean()


def test_a_box_keeps_facet_shading(renderer_small):
    """A mesh with creases (a cube) is not smoothed: each face seen is one flat colour."""
    c = np.array([[(i & 1), (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], float) * 100.0
    quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    faces = np.array([t for q in quads for t in ([q[0], q[1], q[2]], [q[0], q[2], q[3]])])
    s = gc.Scene()
    s.add_mesh(c, faces, color=(0.6, 0.6, 0.6))
    r = renderer_small(160, 120)
    res = r.render(s, gc.Camera.look_at((260.0, -180.0, 240.0), (50.0, 50.0, 50.0)))
    colours = {tuple(p) for p in res.image[res.coverage][:, :3]}
    assert len(colours) <= 3, colours  # three faces seen, one colour each


@pytest.mark.parametrize("culling", ["none", "temporal"])
def test_a_surface_just_below_a_coarse_level_stays_hidden(renderer_small, culling):
    """A surface just below a height field (a grid's top built from a horizon, at Reek) is hidden
    by it at level 0. A coarser level lies within its error of the fine surface, above or below
    it, so drawn at its own depth it dipped below the lower surface wherever it sagged by more than
    the gap, and that surface showed through in patches (the Reek benchmark's worst view: 0.19 % of
    its pixels beyond 4/255, most of what it had). The lit pass writes the fine surface's depth on
    each pixel's ray for coarser levels, so the lower surface stays hidden: what differs is the
    outline (and a pixel where the two surfaces tie in float), not patches inside."""
    x = np.arange(65) * SPACING
    z = 20.0 * np.sin(x[None, :] / 90.0) * np.cos(x[:, None] / 70.0)
    s = gc.Scene()
    h = s.add_heightfield(z, origin=(0.0, 0.0), spacing=(SPACING, SPACING), tiles=(4, 4), color=(0.7, 0.6, 0.4))
    v, f = s.geometry(h)
    errors = s.tile_table()["level_error"][:, :3]  # the levels a lone tile's full border takes
    gap = 0.02 * float(np.nanmax(errors))  # far less than the coarser levels' errors
    s.add_mesh(v - [0.0, 0.0, gap], f, color=(0.0, 0.0, 1.0))
    r = renderer_small(160, 120)
    cam = gc.Camera.look_at((-300.0, -400.0, 500.0), (320.0, 320.0, 0.0))
    full = r.render(s, cam, culling=culling, pixel_threshold=0)
    lod = r.render(s, cam, culling=culling, pixel_threshold=0, lod="screen_error", max_pixel_error=0.5)
    if culling == "temporal":  # its history is now this view
        lod = r.render(s, cam, culling=culling, pixel_threshold=0, lod="screen_error", max_pixel_error=0.5)
    t = s.tile_table()
    coarse = lod.tile_drawn & (lod.tile_level > 0) & (t["object"] == h)
    assert coarse.sum() >= 4, lod.tile_level  # the test needs coarser levels of the height field drawn
    assert not (full.image[..., 2] > full.image[..., 0]).any()  # level 0 hides the blue mesh
    blue = lod.image[..., 2].astype(int) > lod.image[..., 0].astype(int)
    assert blue.sum() <= 2, np.argwhere(blue)[:10]
    diff = np.abs(lod.image.astype(int) - full.image.astype(int)).max(axis=2)
    assert (diff > 4).mean() < 0.001, (diff > 4).mean()


def test_coarse_levels_write_the_fine_depth_only_where_another_object_is_within_their_error(renderer_small):
    """Writing the fine surface's depth costs each fragment its early depth test, so a tile drawn
    at a coarser level writes it only where another object comes within the level's vertical
    error of the tile (its clearance, lod::clearance): alone, no tile does; with a mesh far below
    (beyond every level's error) none does either; with the mesh just below (as in the test
    above), every coarse tile over it does."""
    x = np.arange(65) * SPACING
    z = 20.0 * np.sin(x[None, :] / 90.0) * np.cos(x[:, None] / 70.0)
    cam = gc.Camera.look_at((-300.0, -400.0, 500.0), (320.0, 320.0, 0.0))
    r = renderer_small(160, 120)

    def frame(below: float | None) -> tuple[gc.Scene, gc.RenderResult[gc.RenderStats], int]:
        s = gc.Scene()
        h = s.add_heightfield(z, origin=(0.0, 0.0), spacing=(SPACING, SPACING), tiles=(4, 4))
        if below is not None:
            v, f = s.geometry(h)
            s.add_mesh(v - [0.0, 0.0, below], f, color=(0.0, 0.0, 1.0))
        return s, r.render(s, cam, lod="screen_error", max_pixel_error=0.5), h

    s, alone, h = frame(None)
    errors = s.tile_table()["level_error"]
    top = float(np.nanmax(errors))
    coarse = int(((alone.tile_level > 0) & (s.tile_table()["object"] == h)).sum())
    assert coarse >= 4, alone.tile_level
    assert alone.stats["tiles_fine_depth"] == 0
    s, far, h = frame(10.0 * top + 100.0)
    assert far.stats["tiles_fine_depth"] == 0
    s, near, h = frame(0.02 * top)
    coarse_near = int(((near.tile_level > 0) & (s.tile_table()["object"] == h)).sum())
    assert coarse_near == coarse and near.stats["tiles_fine_depth"] == coarse
    assert "tiles_fine_depth" not in r.render(s, cam).stats  # no lod: no levels
