"""Wells: tubes cut into tiles along the path, culled piece by piece, with levels of detail
(fewer stations, level 0's rings) that show their log's colours per fragment (src/lod/tube.rs)."""

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
    # A straight piece: its end stations only, level 0's rings, with the path's caps; exact, so
    # it is the one level.
    assert (lt[:, 1] == 2 * 8 + np.array([6] + [0] * 14 + [6])).all() and (lt[:, 2:] == 0).all()
    for name in ("level_error", "level_error_z", "level_shading_error"):
        assert (t[name][:, 1] == 0.0).all(), name
    # The prepass proxy is that level, not the fine tube.
    assert (t["tris_coarse"] == lt[:, 1]).all()


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
    silhouettes may flip (the outline moves by up to the error), the inside shades as the fine
    tube does (level 0's rings and radial normals at every level), coloured by its log."""
    path, log = deviated_with_log()
    s = gc.Scene()
    s.add_well(path, radius=20.0, values=log, cmap="viridis")
    r = renderer_small(320, 240)
    for az, el in ((30.0, 20.0), (160.0, 45.0)):
        cam = gc.Camera.fit(s, azimuth=az, elevation=el, fov_y=35.0)
        full = r.render(s, cam, culling="none")
        lod = r.render(s, cam, culling="none", lod="screen_error", max_pixel_error=0.5)
        assert lod.stats["triangles_drawn"] < 0.2 * full.stats["triangles_drawn"]
        assert (lod.tile_level > 0).all()
        assert lod.stats["lod_max_error_px"] <= 0.5
        lit_full, lit_lod = np.isfinite(full.depth).sum(), np.isfinite(lod.depth).sum()
        assert lit_full > 800 and abs(lit_lod - lit_full) <= 0.01 * lit_full, (lit_full, lit_lod)
        inside = interior(full, lod)
        assert inside.sum() > 200
        diff = np.abs(full.image.astype(int) - lod.image.astype(int)).max(axis=2)
        # Inside, within 4/255: the shade within MAX_TUBE_SHADING_LEVELS at the tube's middle
        # (more towards its outline), the log's colours displaced with the surface.
        assert diff[inside].max() <= 4, diff[inside].max()
        assert (diff > 0).mean() <= 0.01, (diff > 0).mean()


def test_a_log_is_coloured_per_fragment_at_every_level(renderer_small):
    """A straight well whose log steps between two values every 8 stations: its one level keeps
    only its tiles' end stations, yet shows every step of the log where level 0 shows it (the
    level interpolates the station, the lit pass looks the log up): the same picture."""
    z = np.arange(0.0, -512.5, -1.0)
    path = np.column_stack([np.full_like(z, 500.0), np.full_like(z, 500.0), z])
    log = np.where((np.arange(len(z)) // 8) % 2 == 0, 0.1, 0.3)
    log[300:340] = np.nan
    s = gc.Scene()
    w = s.add_well(path, radius=6.0, values=log, cmap="viridis", clim=(0.0, 0.4))
    t = s.tile_table()
    assert (t["level_triangles"][t["object"] == w][:, 1] <= 2 * 8 + 6).all()
    r = renderer_small(120, 320)
    cam = gc.Camera.look_at((900.0, 500.0, -256.0), (500.0, 500.0, -256.0), projection="orthographic",
                            ortho_height=540.0)
    full = r.render(s, cam, culling="none")
    lod = r.render(s, cam, culling="none", lod="screen_error", max_pixel_error=0.5)
    assert (lod.tile_level == 1).all() and lod.stats["triangles_drawn"] <= 4 * (2 * 8 + 6)
    np.testing.assert_array_equal(np.isfinite(full.depth), np.isfinite(lod.depth))
    diff = np.abs(full.image.astype(int) - lod.image.astype(int)).max(axis=2)
    # (On a step the log changes by half its range within a station, a pixel or so: there the
    # station, interpolated over a longer triangle, may round to the next colour-map row, at most
    # 2 levels of viridis, in at most a pixel a step.)
    assert diff.max() <= 2 and (diff > 0).sum() <= 64, (diff.max(), (diff > 0).sum())
    # The steps are there: down the tube's axis the colour changes some 64 times, and the no-data
    # run shows in the NaN colour.
    col = full.image[:, full.image.shape[1] // 2, :3].astype(int)
    lit = np.isfinite(full.depth[:, full.image.shape[1] // 2])
    changes = (np.abs(np.diff(col[lit], axis=0)).max(axis=1) > 30).sum()
    assert changes >= 50, changes


def _rows_and_cols(res) -> tuple[int, int]:
    """Rows and columns of the image that the well covers (finite depth)."""
    lit = np.isfinite(res.depth)
    return int(lit.any(axis=1).sum()), int(lit.any(axis=0).sum())


@pytest.mark.parametrize("z_scale", [5.0, 10.0])
def test_exaggeration_stretches_the_path_not_the_tube(renderer_small, z_scale):
    """A level well of radius 10 m seen from the side: exaggerated, it stays a tube as thick on
    screen as at z_scale 1 (its rings are not exaggerated), where stretching it whole would make
    it z_scale times as tall; a vertical well's length grows z_scale times, its width not."""
    r = renderer_small(200, 200)

    def side(s: gc.Scene, zs: float) -> tuple[int, int]:
        # Orthographic from the south, 400 m of view: 2 m a pixel, whatever the exaggeration.
        cam = gc.Camera.look_at((500.0, -3000.0, -1500.0), (500.0, 0.0, -1500.0), projection="orthographic",
                                ortho_height=400.0, z_scale=zs)
        return _rows_and_cols(r.render(s, cam, culling="none"))

    x = np.linspace(300.0, 700.0, 201)
    level = gc.Scene()
    level.add_well(np.column_stack([x, np.zeros_like(x), np.full_like(x, -1500.0)]), radius=10.0)
    flat, tall = side(level, 1.0), side(level, z_scale)
    assert 8 <= flat[0] <= 12 and abs(tall[0] - flat[0]) <= 1, (flat, tall)
    assert abs(tall[1] - flat[1]) <= 1
    # Vertical, 30 m long about the view's centre (flat caps: 15 pixels): z_scale times as long
    # on screen, as wide.
    z = np.linspace(-1485.0, -1515.0, 61)
    vertical = gc.Scene()
    vertical.add_well(np.column_stack([np.full_like(z, 500.0), np.zeros_like(z), z]), radius=10.0)
    one, ex = side(vertical, 1.0), side(vertical, z_scale)
    assert abs(ex[1] - one[1]) <= 1, (one, ex)
    assert abs(one[0] - 15) <= 1 and abs(ex[0] - min(15 * z_scale, 200)) <= 2, (one, ex)


def test_an_exaggerated_deviated_well_renders_the_same_in_every_exact_mode(renderer_small):
    """Tubes drawn with unexaggerated rings stay within their tiles' boxes: every exact mode gives
    `none`'s image, with a horizon in front hiding part of the well, at z_scale 1, 5 and 10 and
    with flattening."""
    path, log = deviated_with_log()
    s = gc.Scene()
    s.add_well(path, radius=20.0, values=log, cmap="viridis")
    lo, hi = np.asarray(s.bounds[0]), np.asarray(s.bounds[1])
    z = np.full((21, 21), 0.5 * (lo[2] + hi[2]))
    s.add_heightfield(z, origin=(lo[0], lo[1]), spacing=((hi[0] - lo[0]) / 20, (hi[1] - lo[1]) / 20), tiles=(2, 2))
    r = renderer_small(160, 120)
    for z_scale in (0.5, 1.0, 5.0, 10.0):
        for az, el in ((30.0, 10.0), (200.0, 35.0)):
            cam = gc.Camera.fit(s, azimuth=az, elevation=el, z_scale=z_scale)
            ref = r.render(s, cam, culling="none")
            for mode in EXACT:
                got = r.render(s, cam, culling=mode, pixel_threshold=0)
                assert np.array_equal(got.image, ref.image), (z_scale, az, mode)
                assert np.array_equal(got.depth, ref.depth), (z_scale, az, mode)
