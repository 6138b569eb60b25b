"""Renderer.pass_triangles: a frame's lit draws split into render passes of a bounded number of
triangles (memory on CPU drivers) give the same image, depth and per-tile counts as one pass."""

import numpy as np
import pytest

import geocull as gc
from geocull.data import stacked_test_scene, standard_views

METHODS = [
    dict(culling="none"),
    dict(culling="none", lod="screen_error", max_pixel_error=1.0),
    dict(culling="three_pass", pixel_threshold=0),
    dict(culling="three_pass", pixel_threshold=10, prepass_scale=1.0, conservative=False),
    dict(culling="temporal", pixel_threshold=0),
    dict(culling="oracle"),
]


@pytest.fixture(scope="module")
def scene_and_views():
    spec = stacked_test_scene(n=64, n_horizons=4, with_faults=True, seed=3)
    scene = spec.build(tiles=(8, 8), coarse_factor=25)
    views = [gc.Camera.look_at(**kw) for _, kw in standard_views(spec, aspect=96 / 72)[:3]]
    return scene, views


@pytest.mark.parametrize("kw", METHODS, ids=lambda k: "-".join(str(v) for v in k.values()))
def test_split_passes_draw_the_same_frame(scene_and_views, kw):
    scene, views = scene_and_views
    one, split = gc.Renderer(96, 72), gc.Renderer(96, 72)
    split.pass_triangles = 1500  # the scene has ~33,000 triangles: about 20 passes
    for cam in views:
        for _ in range(2 if kw["culling"] == "temporal" else 1):  # temporal: its history too
            a, b = one.render(scene, cam, **kw), split.render(scene, cam, **kw)
        assert a.stats["draw_passes"] == 1
        assert b.stats["draw_passes"] > 5
        np.testing.assert_array_equal(b.image, a.image)
        np.testing.assert_array_equal(b.depth, a.depth)
        np.testing.assert_array_equal(b.tile_pixels, a.tile_pixels)
        np.testing.assert_array_equal(b.tile_drawn, a.tile_drawn)
        assert b.stats["triangles_drawn"] == a.stats["triangles_drawn"]


def test_each_pass_holds_at_most_the_bound_or_one_tile(scene_and_views):
    scene, views = scene_and_views
    r = gc.Renderer(96, 72)
    per_tile = scene.tile_table()["level_triangles"][:, 0].astype(int)
    for bound in (1, int(per_tile.max()), 5000, 10**9):
        r.pass_triangles = bound
        res = r.render(scene, views[0], culling="none")
        # the fewest passes that respect the bound, greedily in tile order (a tile over it alone)
        passes, acc = 1, 0
        for t in per_tile:
            if acc and t and acc + t > bound:
                passes, acc = passes + 1, 0
            acc += t
        assert res.stats["draw_passes"] == passes, bound


def test_bad_bounds_are_refused_and_none_restores_one_pass():
    r = gc.Renderer(16, 12)
    assert r.pass_triangles is None
    for bad in (0, -1):
        with pytest.raises(gc.InputError, match="pass_triangles"):
            r.pass_triangles = bad
    for bad in (1.5, "10", True):
        with pytest.raises(gc.InputError, match="pass_triangles"):
            r.pass_triangles = bad
    r.pass_triangles = 7
    assert r.pass_triangles == 7
    r.pass_triangles = None
    assert r.pass_triangles is None
    assert gc.Renderer(16, 12, pass_triangles=5).pass_triangles == 5
    with pytest.raises(gc.InputError, match="pass_triangles"):
        gc.Renderer(16, 12, pass_triangles=0)
