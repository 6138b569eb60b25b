"""A reservoir grid coloured by a cell property keeps its picture at every level of detail: merged
faces colour each fragment from its own cell (``grid::cells``), so coarser levels change geometry
within their error and colours not at all. Known answers on box grids (exact at every level)."""

from __future__ import annotations

import numpy as np
from tests.test_grid import box_corners

import geocull as gc

W, H = 160, 120


def differing(a: gc.RenderResult, b: gc.RenderResult) -> tuple[float, float]:
    """Percent of pixels that differ at all, and by more than 4/255."""
    d = np.abs(a.image.astype(int) - b.image.astype(int)).max(axis=-1)
    return 100.0 * float((d > 0).mean()), 100.0 * float((d > 4).mean())


def test_a_checkerboard_survives_the_coarsest_level(renderer_small):
    # 2 x 16 x 16 cells of 10 m, values alternating like a checkerboard: every merged face covers
    # cells of both values. A colour per merged face (their mean) would show one grey.
    k, j, i = np.meshgrid(np.arange(2), np.arange(16), np.arange(16), indexing="ij")
    values = ((i + j + k) % 2).astype(float)
    s = gc.Scene()
    s.add_grid(box_corners(2, 16, 16), blocks=(8, 8), values=values, clim=(0, 1), cmap="viridis")
    cam = gc.Camera.look_at((80, -60, 120), (80, 80, -10), fov_y=50)
    r = renderer_small(W, H)
    full = r.render(s, cam, grid_lod="full")
    far = gc.Camera.look_at((80, -20000, 8000), (80, 80, -10), fov_y=2)
    coarse = r.render(s, far, grid_lod="distance", alpha=8, lam=3)
    assert coarse.stats["grid_cells_level3"] == 2 * 4, coarse.stats  # the coarsest level
    # The same level drawn from the near camera: every block at level 3 (alpha, lam at their
    # smallest still put blocks this near at level 0, so force it by a huge pixel error).
    lod = r.render(s, cam, grid_lod="screen_error", max_pixel_error=1e6)
    assert lod.stats["grid_cells_level3"] == 2 * 4, lod.stats
    assert lod.stats["triangles_drawn"] < full.stats["triangles_drawn"] / 4
    any_diff, big = differing(full, lod)
    assert big <= 0.5, (any_diff, big)
    # The same colours as level 0 (two values, a few facet shades), none of them a mean of both.
    def colours(res: gc.RenderResult) -> set[tuple[int, ...]]:
        return {tuple(int(x) for x in c) for c in np.unique(res.image[res.coverage][:, :3], axis=0)}

    assert colours(lod) == colours(full)


def test_irregular_grid_at_half_a_pixel_changes_at_most_half_a_percent(renderer_small):
    # A faulted grid of irregular cells coloured by random values, at the renderer's half-pixel
    # screen error: at most 0.5 % of pixels differ from level 0, with fewer triangles.
    g = gc.data.faulted_grid(ni=48, nj=40, nk=6, seed=3)
    rng = np.random.default_rng(1)
    values = rng.random(g["active"].shape)
    s = gc.Scene()
    s.add_grid(g["corners"], active=g["active"], region=g["region"], values=values, blocks=(8, 8))
    lo, hi = (np.array(b) for b in s.bounds)
    c = (lo + hi) / 2
    ext = float(np.linalg.norm(hi - lo))
    r = renderer_small(320, 256)
    for eye in ([1.2, -2.0, 1.2], [-0.8, 1.5, 2.0]):
        cam = gc.Camera.look_at(tuple(c + ext * np.array(eye)), tuple(c), fov_y=30)
        full = r.render(s, cam, grid_lod="full")
        lod = r.render(s, cam, grid_lod="screen_error", max_pixel_error=0.5)
        assert lod.stats["triangles_drawn"] < full.stats["triangles_drawn"]
        any_diff, big = differing(full, lod)
        assert any_diff <= 0.5, (eye, any_diff, big)
