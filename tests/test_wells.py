"""Wells: tubes cut into tiles along the path, culled piece by piece, with levels of detail
(fewer sides, fewer stations) that keep their log's colours (src/lod/tube.rs)."""

from __future__ import annotations

import numpy as np
import pytest

import geocull as gc

EXACT = ("three_pass", "temporal", "frustum", "horizon")


def vertical_well(top: float, bottom: float, step: float = 1.0) -> np.ndarray:
    z = np.arange(top, bottom - 1e-9, -step)
    return np.column_stack([np.full_like(z, 500.0), np.full_like(z, 500.0), z])


def scene_with_buried_well() -> tuple[gc.Scene, int, int]:
    """A flat opaque horizon at z = 0 over 1 km², and a vertical well from z = 250 down to
    z = -1798 (1 m stations: 2,048 segments, 16 tiles of 128): the top tile stands above the
    horizon, the second crosses it (z = 122 to -6), the other 14 lie wholly under it."""
    s = gc.Scene()
    h = s.add_heightfield(np.zeros((41, 41)), origin=(0.0, 0.0), spacing=(25.0, 25.0), tiles=(4, 4))
    w = s.add_well(vertical_well(250.0, -1798.0), radius=5.0, color=(0.9, 0.2, 0.1))
    return s, h, w


def test_a_well_hidden_behind_a_horizon_is_culled_piece_by_piece(renderer_small):
    s, _, w = scene_with_buried_well()
    t = s.tile_table()
    well = t["object"] == w
    assert well.sum() == 16
    below = well & (t["bbox_max"][:, 2] < 0.0)
    above = well & (t["bbox_min"][:, 2] > 0.0)
    assert below.sum() == 14 and above.sum() == 1  # one tile straddles z = 0
    r = renderer_small(160, 120)
    cam = gc.Camera.look_at((-900.0, -700.0, 1200.0), (500.0, 500.0, 0.0), fov_y=40.0)
    ref = r.render(s, cam, culling="none")
    for mode in ("three_pass", "temporal"):
        # temporal's second frame repeats the first: it draws the tiles seen, untested.
        frames = [r.render(s, cam, culling=mode, pixel_threshold=0) for _ in range(2)]
        for res in frames:
            np.testing.assert_array_equal(res.image, ref.image, err_msg=mode)
            assert not res.tile_drawn[below].any(), mode
        # The tested frame keeps the piece above the horizon (its box shows; the tube itself is
        # thinner than a pixel here, so a repeat leaves it out).
        assert frames[0].tile_drawn[above].all(), mode


def test_levels_cut_a_straight_well_to_a_few_triangles():
    s = gc.Scene()
    w = s.add_well(vertical_well(0.0, -2048.0), radius=10.0)
    t = s.tile_table()[s.tile_table()["object"] == w]
    assert len(t) == 16
    lt = t["level_triangles"]
    assert (lt[:, 0] == 2 * 128 * 8 + np.array([6] + [0] * 14 + [6])).all()
    # A straight piece: its end stations only, 6 then 4 sides, capped.
    assert (lt[:, 1] == 2 * 6 + 2 * 4).all() and (lt[:, 2] == 2 * 4 + 2 * 2).all()
    # The error: how far the level's polygon (of the octagon's perimeter) lies from the octagon.
    def gap(sides: int) -> float:
        r = 10.0 * 8 * np.sin(np.pi / 8) / (sides * np.sin(np.pi / sides))
        return max(r - 10.0 * np.cos(np.pi / 8), 10.0 - r * np.cos(np.pi / sides))

    err = t["level_error"]
    assert err[:, 1] == pytest.approx(gap(6), rel=1e-5)
    assert err[:, 2] == pytest.approx(gap(4), rel=1e-5)
    assert (t["level_shading_error"][:, 1:3] < 1e-6).all()
    # The prepass proxy is a level, not the fine tube.
    assert (t["tris_coarse"] <= 20).all()


def deviated_with_log(n: int = 4000, seed: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """A well 0.5 m a station: vertical, building up to 50°, then straight; a porosity log with
    data over a third of its length (noise about a trend), NaN elsewhere."""
    s = np.arange(n) * 0.5
    inc = np.clip((s - 300.0) / 400.0, 0.0, 1.0) * np.radians(50.0)
    d = np.column_stack([np.sin(inc), 0.3 * np.sin(inc), -np.cos(inc)])
    d /= np.linalg.norm(d, axis=1)[:, None]
    path = np.vstack([[0.0, 0.0, 0.0], np.cumsum(0.5 * d[:-1], axis=0)]) + [461_000.0, 5_932_000.0, -1200.0]
    rng = np.random.default_rng(seed)
    log = np.full(n, np.nan)
    k = slice(n // 3, 2 * n // 3)
    log[k] = 0.2 + 0.05 * np.sin(s[k] / 20.0) + rng.normal(0.0, 0.01, size=k.stop - k.start)
    return path, log


def interior(res_a, res_b) -> np.ndarray:
    """Pixels whose 3 x 3 neighbourhood is surface in both images (not on a silhouette)."""
    from scipy.ndimage import binary_dilation

    bg = ~np.isfinite(res_a.depth) | ~np.isfinite(res_b.depth)
    return ~binary_dilation(bg, np.ones((3, 3), bool))


def test_screen_error_levels_keep_the_picture(renderer_small):
    """A tube 4-6 pixels wide: at 0.5 px its tiles take level 1 or coarser. Pixels on its
    silhouettes flip (the outline moves by up to the error), the inside shades as the fine tube
    does (radial normals at every level), and the outline keeps its width on average (equal
    perimeter)."""
    path, _ = deviated_with_log()
    s = gc.Scene()
    s.add_well(path, radius=20.0, color=(0.8, 0.5, 0.2))
    r = renderer_small(320, 240)
    for az, el in ((30.0, 20.0), (160.0, 45.0)):
        cam = gc.Camera.fit(s, azimuth=az, elevation=el, fov_y=35.0)
        full = r.render(s, cam, culling="none")
        lod = r.render(s, cam, culling="none", lod="screen_error", max_pixel_error=0.5)
        assert lod.stats["triangles_drawn"] < 0.5 * full.stats["triangles_drawn"]
        assert (lod.tile_level > 0).sum() >= 0.5 * len(lod.tile_level)
        assert lod.stats["lod_max_error_px"] <= 0.5
        lit_full, lit_lod = np.isfinite(full.depth).sum(), np.isfinite(lod.depth).sum()
        assert lit_full > 800 and abs(lit_lod - lit_full) <= 0.1 * lit_full, (lit_full, lit_lod)
        inside = interior(full, lod)
        assert inside.sum() > 200
        diff = np.abs(full.image.astype(int) - lod.image.astype(int)).max(axis=2)
        assert diff[inside].max() <= 6, diff[inside].max()


def test_a_log_keeps_its_stations_at_every_level():
    """Stations with data stay where their value is off the line through their neighbours' by
    more than half a colour-map row: a noisy log keeps them all, its no-data runs collapse."""
    path, log = deviated_with_log()
    s = gc.Scene()
    w = s.add_well(path, radius=20.0, values=log, cmap="viridis")
    t = s.tile_table()
    t = t[t["object"] == w]
    logged = np.isfinite(log)
    for row in t:
        a = row["ix"] * 128
        seg = logged[a : a + 129]
        n = row["level_triangles"]
        if seg.all():
            # Noise of 0.01 against a tolerance of 1/512 of the range: nearly every station
            # stays at every level (a few fall near the line through their neighbours), only
            # the sides drop, to 3 at the fewest.
            assert (n[n > 0] >= 0.9 * 2 * 128 * 3).all(), n
        elif not seg.any() and (row["level_triangles"] > 0).sum() > 1:
            assert n[n > 0].min() < 0.05 * n[0]
