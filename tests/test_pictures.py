"""Pictures a geoscientist can read (issue 38): one depth colour range shared by the scene, figures
with colour bars, scale bar and north arrow, and the renderer's background."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import geocull as gc

W, H = 96, 64


def ramp(z0: float, n: int = 51, dx: float = 20.0) -> np.ndarray:
    """(11, n) heights falling 0.1 m per metre along x from ``z0``: the same slope everywhere, so the
    same shading, and a colour that tells depth alone."""
    return np.repeat((z0 - 0.1 * dx * np.arange(n))[None, :], 11, axis=0)


def top_down() -> gc.Camera:
    """Orthographic, straight down on the two ramps (x 0..1000, y 0..500), north up."""
    return gc.Camera.look_at((500, 250, 2000), (500, 250, -1000), up=(0, 1, 0), projection="orthographic",
                             ortho_height=700.0)


def pixel(x: float, y: float) -> tuple[int, int]:
    """(row, column) of world (x, y) in top_down()'s image."""
    m = 700.0 / H
    return int(round(H / 2 - (y - 250) / m - 0.5)), int(round(W / 2 + (x - 500) / m - 0.5))


def two_horizons(**kw_b) -> tuple[gc.Scene, int, int]:
    s = gc.Scene()
    a = s.add_heightfield(ramp(-1000.0), origin=(0, 0), spacing=(20, 20), name="top")  # -1000 .. -1100
    b = s.add_heightfield(ramp(-1050.0), origin=(0, 300), spacing=(20, 20), name="base", **kw_b)  # -1050 .. -1150
    return s, a, b


def test_horizons_coloured_by_z_share_the_scene_depth_range(renderer_small):
    s, a, b = two_horizons()
    assert s.depth_range() == pytest.approx((-1150.0, -1000.0))
    for i in (a, b):
        info = s.object_info(i)
        assert info["color_by"] == "z" and info["clim"] == pytest.approx((-1150.0, -1000.0))
    res = renderer_small(W, H).render(s, top_down(), culling="none")
    img = res.image[..., :3].astype(int)
    # z = -1075 lies at x = 750 on the top horizon and at x = 250 on the base: the same colour.
    ya, yb = 100.0, 400.0
    for x, y in ((750, ya), (250, yb)):
        assert res.depth[pixel(x, y)] == pytest.approx(2000 + 1075, abs=2)  # the eye is at z = 2000
    same_a, same_b = img[pixel(750, ya)], img[pixel(250, yb)]
    assert np.abs(same_a - same_b).max() <= 2, (same_a, same_b)
    # Different depths on one horizon: different colours (the test can tell colours apart).
    assert np.abs(img[pixel(100, ya)] - img[pixel(900, ya)]).max() > 40
    # Over its own range alone (the old default) the base's -1075 would take another colour.
    own = gc.Scene()
    own.add_heightfield(ramp(-1050.0), origin=(0, 300), spacing=(20, 20))
    alone = renderer_small(W, H).render(own, top_down(), culling="none").image[..., :3].astype(int)
    assert np.abs(alone[pixel(250, yb)] - same_a).max() > 40


def test_the_depth_range_follows_adds_removals_and_recolouring():
    s, a, b = two_horizons()
    c = s.add_heightfield(ramp(-900.0), origin=(0, 600), spacing=(20, 20))  # -900 .. -1000: widens it
    assert all(s.object_info(i)["clim"] == pytest.approx((-1150.0, -900.0)) for i in (a, b, c))
    s.remove(c)
    assert all(s.object_info(i)["clim"] == pytest.approx((-1150.0, -1000.0)) for i in (a, b))
    s.set_color(b, (1, 0, 0))  # a flat colour leaves the range
    assert s.object_info(a)["clim"] == pytest.approx((-1100.0, -1000.0)) and s.depth_range() == (-1100.0, -1000.0)
    s.set_color_by(b, "z", cmap="plasma")  # back by z without clim: shares again, with its own map
    assert s.object_info(a)["clim"] == s.object_info(b)["clim"] == pytest.approx((-1150.0, -1000.0))
    assert s.object_info(b)["cmap"] == "plasma"
    s.translate(b, (0, 0, -500))  # colour by z ignores translations (as documented)
    assert s.object_info(a)["clim"] == pytest.approx((-1150.0, -1000.0))
    # A copy and a pickle keep sharing: a deeper horizon added to either widens every range.
    for t in (s.copy(), pickle.loads(pickle.dumps(s))):
        d = t.add_heightfield(ramp(-1200.0), origin=(0, 900), spacing=(20, 20))
        assert all(t.object_info(i)["clim"] == pytest.approx((-1300.0, -1000.0)) for i in (a, b, d))
    assert s.object_info(a)["clim"] == pytest.approx((-1150.0, -1000.0))  # the original is untouched


def test_a_clim_of_its_own_wins():
    s, a, b = two_horizons(clim=(-2000.0, -500.0))
    assert s.object_info(b)["clim"] == (-2000.0, -500.0)
    assert s.object_info(a)["clim"] == pytest.approx((-1100.0, -1000.0))  # b is not part of the range
    s.set_color_by(a, "z", clim=(-1100.0, -1090.0))
    assert s.object_info(a)["clim"] == (-1100.0, -1090.0) and s.depth_range() is None
    values = s.add_heightfield(ramp(-1000.0), origin=(0, 600), spacing=(20, 20), values=np.ones((11, 51)))
    assert s.object_info(values)["color_by"] == "values" and s.depth_range() is None
    with pytest.raises(gc.InputError, match="^label"):
        s.add_heightfield(ramp(-1000.0), values=np.ones((11, 51)), label=3)


def colour_bars(fig) -> list:
    """The colour bars of a figure from RenderResult.figure, left to right."""
    return [ax._colorbar for ax in fig.axes if ax.get_label() == "colorbar"]


def by_gid(fig, gid: str) -> list:
    return [a for ax in fig.axes for a in ax.get_children() if a.get_gid() == gid]


def picture_scene() -> gc.Scene:
    """Two horizons by z (the shared range), one by its own clim, a porosity map, a flat fault and a
    horizon far outside the view."""
    s, a, b = two_horizons()
    s.add_heightfield(ramp(-1000.0), origin=(0, 600), spacing=(20, 20), values=np.linspace(0.1, 0.3, 51)[None, :]
                      * np.ones((11, 1)), cmap="seismic", label="porosity")
    s.add_heightfield(ramp(-1000.0), origin=(0, 900), spacing=(20, 20), clim=(-1200.0, -900.0))
    s.add_mesh([[0, 1200, -900], [1000, 1200, -900], [0, 1250, -1000]], [[0, 1, 2]], kind="fault", color=(1, 0, 1))
    s.add_heightfield(ramp(-1000.0), origin=(50_000, 0), spacing=(20, 20), cmap="plasma")  # not in the view
    return s


def test_figure_has_one_colour_bar_per_colour_map_used_with_its_limits(renderer_small):
    pytest.importorskip("matplotlib")
    s = picture_scene()
    cam = gc.Camera.look_at((500, 700, 3000), (500, 700, -1000), up=(0, 1, 0), projection="orthographic",
                            ortho_height=1500.0)
    res = renderer_small(W, H).render(s, cam, culling="none")
    assert {c["object"] for c in res.colorings} == {0, 1, 2, 3}  # the fault is flat, the last one off-screen
    fig = res.figure(title="Gullfaks")
    bars = colour_bars(fig)
    got = sorted((cb.ax.get_ylabel(), cb.cmap.name, tuple(round(x, 6) for x in cb.mappable.get_clim()))
                 for cb in bars)
    assert s.object_info(2)["clim"] == pytest.approx((0.1, 0.3))
    assert got == sorted([("depth (m)", "viridis", (-1150.0, -1000.0)),  # the two horizons: one bar
                          ("porosity", "seismic", (0.1, 0.3)),
                          ("depth (m)", "viridis", (-1200.0, -900.0))])
    # Each bar shows the colours the objects were drawn with: the core's 256 rows of the map.
    import matplotlib

    seismic = [cb for cb in bars if cb.ax.get_ylabel() == "porosity"][0]
    np.testing.assert_allclose(seismic.cmap(np.linspace(0, 1, 256))[:, :3],
                               matplotlib.colormaps["seismic"](np.linspace(0, 1, 256))[:, :3], atol=1e-6)
    # Depth bars count depth = -z: the tick at z = -1100 reads 1100.
    depth = [cb for cb in bars if cb.mappable.get_clim() == pytest.approx((-1150.0, -1000.0))][0]
    assert depth.ax.yaxis.get_major_formatter()(-1100.0, 0) == "1100"
    assert fig.axes[0].get_title() == "Gullfaks"
    assert by_gid(fig, "image")[0].get_array().shape == (H, W, 3)
    # Without colour bars, scale bar and arrow: the image alone.
    bare = res.figure(colorbar=False, scale_bar=False, north_arrow=False)
    assert colour_bars(bare) == [] and not by_gid(bare, "scale_bar") and not by_gid(bare, "north_arrow")


def test_an_elevation_colour_bar_and_a_log_named_by_its_values(renderer_small):
    pytest.importorskip("matplotlib")
    s = gc.Scene()
    s.add_heightfield(ramp(300.0), spacing=(20, 20))  # terrain: 300 .. 200 m above datum
    path = np.array([[500, 250, 400], [500, 250, -500]], float)
    s.add_well(path, radius=30, values=np.array([0.0, 1.0]), cmap="gray")  # no label: "values"
    cam = gc.Camera.look_at((500, 250, 2000), (500, 250, 0), up=(0, 1, 0), projection="orthographic",
                            ortho_height=1200.0)
    res = renderer_small(W, H).render(s, cam, culling="none")
    labels = sorted(cb.ax.get_ylabel() for cb in colour_bars(res.figure()))
    assert labels == ["elevation (m)", "values"]


def test_scale_bar_and_north_arrow_where_the_projection_allows(renderer_small):
    pytest.importorskip("matplotlib")
    s = picture_scene()
    r = renderer_small(W, H)
    top = gc.Camera.look_at((500, 700, 3000), (500, 700, -1000), up=(0, 1, 0), projection="orthographic",
                            ortho_height=1500.0)
    fig = r.render(s, top, culling="none").figure()
    (bar,), (label,) = by_gid(fig, "scale_bar"), by_gid(fig, "scale_bar_label")
    mpp = 1500.0 / H  # metres per pixel of the orthographic view
    assert label.get_text() == "200 m"  # a fifth of the width is 0.2 * 96 * 23.4 m = 450 m: 200 m
    assert bar.get_width() == pytest.approx(200.0 / mpp)
    assert by_gid(fig, "north_arrow_label")[0].get_text() == "N"
    assert north(fig) == pytest.approx((0.0, 1.0), abs=1e-9)  # north up

    # Straight down with east up in the image (the map turned a quarter counter-clockwise): north
    # points left, as the image shows: the northern objects (the fault at y = 1200) lie left of the
    # southern ones (y = 0).
    turned = gc.Camera.look_at((500, 700, 3000), (500, 700, -1000), up=(1, 0, 0), projection="orthographic",
                               ortho_height=1500.0)
    res = r.render(s, turned, culling="none")
    assert north(res.figure()) == pytest.approx((-1.0, 0.0), abs=1e-9)
    img = res.image.astype(int)
    fault = (img[..., 0] > 100) & (img[..., 1] < 60) & (img[..., 2] > 100)  # the flat magenta fault
    cols = np.nonzero(res.coverage)[1]
    assert fault.any() and np.nonzero(fault)[1].max() < cols.max() - W // 4

    # Perspective straight down on one flat level: the bar is true at that distance.
    flat = gc.Scene()
    flat.add_heightfield(np.full((11, 11), -1000.0), origin=(0, 0), spacing=(100, 100))
    down = gc.Camera.look_at((500, 500, 0), (500, 500, -1000), up=(0, 1, 0), fov_y=40.0)
    res = r.render(flat, down, culling="none")
    (bar,) = by_gid(res.figure(), "scale_bar")
    mpp = 2 * 1000.0 * np.tan(np.radians(20.0)) / H
    length = float(by_gid(res.figure(), "scale_bar_label")[0].get_text().split()[0])
    assert bar.get_width() == pytest.approx(length / mpp, rel=1e-3)
    # An oblique perspective view has no one scale, nor one north direction.
    oblique = gc.Camera.orbit((500, 700, -1000), azimuth=30, elevation=30, distance=3000)
    fig = r.render(s, oblique, culling="none").figure()
    assert not by_gid(fig, "scale_bar") and not by_gid(fig, "north_arrow")
    assert len(colour_bars(fig)) >= 1
    # An orthographic side view looking north: a scale bar (x is horizontal), north along the view axis.
    side = gc.Camera.look_at((500, -3000, -1000), (500, 700, -1000), projection="orthographic", ortho_height=1500.0)
    fig = r.render(s, side, culling="none").figure()
    assert by_gid(fig, "scale_bar") and not by_gid(fig, "north_arrow")


def north(fig) -> tuple[float, float]:
    """The unit direction (x right, y up) of the figure's north arrow, tail to tip, in display space."""
    (ann,) = by_gid(fig, "north_arrow")
    tip = np.asarray(ann.xycoords.transform(ann.xy))
    tail = np.asarray(ann.anncoords.transform(ann.xyann))
    d = tip - tail
    return tuple(d / np.linalg.norm(d))


def test_background_default_gradient_named_and_any_rgb(monkeypatch):
    monkeypatch.delenv("GEOCULL_BACKGROUND", raising=False)  # conftest makes the suite's default black
    s, _a, _b = two_horizons()
    black = gc.Renderer(W, H, background="black").render(s, top_down(), culling="none")
    cov = black.coverage
    assert cov.any() and (~cov).any() and (black.image[~cov] == (0, 0, 0, 255)).all()  # the core's own image

    def check(r, top, bottom):
        res = r.render(s, top_down(), culling="none")
        np.testing.assert_array_equal(res.depth, black.depth)
        np.testing.assert_array_equal(res.image[cov], black.image[cov])  # surfaces untouched
        assert (res.image[..., 3] == 255).all()
        t = np.linspace(0, 1, H)[:, None]
        want = np.round(255 * ((1 - t) * np.asarray(top) + t * np.asarray(bottom))).astype(np.uint8)
        rows, cols = np.nonzero(~cov)
        np.testing.assert_array_equal(res.image[rows, cols, :3], want[rows])
        return res

    default = gc.Renderer(W, H)
    assert default.background == gc.renderer.BACKGROUNDS["gradient"]
    res = check(default, *gc.renderer.BACKGROUNDS["gradient"])
    top, bottom = res.image[0, 0, :3].astype(int), res.image[-1, 0, :3].astype(int)
    assert (top > bottom).all() and top.min() >= 220 and bottom.min() >= 170  # light grey, lighter on top
    assert np.ptp(top) <= 3 and np.ptp(bottom) <= 3  # neutral
    check(gc.Renderer(W, H, background="white"), (1, 1, 1), (1, 1, 1))
    r = gc.Renderer(W, H, background=(0.2, 0.4, 0.6))
    check(r, (0.2, 0.4, 0.6), (0.2, 0.4, 0.6))
    r.background = ((1, 0, 0), (0, 0, 1))  # settable, a (top, bottom) pair
    check(r, (1, 0, 0), (0, 0, 1))
    r.background = "black"
    np.testing.assert_array_equal(r.render(s, top_down(), culling="none").image, black.image)
    monkeypatch.setenv("GEOCULL_BACKGROUND", "0.5,0.5,0.5")  # for a whole program or test run
    check(gc.Renderer(W, H), (0.5, 0.5, 0.5), (0.5, 0.5, 0.5))
    check(gc.Renderer(W, H, background="white"), (1, 1, 1), (1, 1, 1))  # the argument wins


def test_background_errors_name_the_argument(monkeypatch):
    for bad, msg in (("pink", "^background: 'pink'"), ((1.5, 0, 0), "^background: colours must lie in"),
                     ((0.1, 0.2), r"^background: shape \(2,\)"), (object(), "^background:")):
        with pytest.raises(gc.InputError, match=msg):
            gc.Renderer(8, 8, background=bad)
    r = gc.Renderer(8, 8, background="white")
    with pytest.raises(gc.InputError, match="^background"):
        r.background = (0, 0, 2)
    assert r.background == ((1.0, 1.0, 1.0), (1.0, 1.0, 1.0))
    monkeypatch.setenv("GEOCULL_BACKGROUND", "purple")
    with pytest.raises(gc.InputError, match="^GEOCULL_BACKGROUND: 'purple'"):
        gc.Renderer(8, 8)


def test_background_under_isosurfaces_and_what_translucent_slices_keep(renderer_small):
    x, y, z = np.meshgrid(np.arange(20.0), np.arange(20.0), np.arange(20.0), indexing="ij")
    vol = gc.Volume(np.sqrt((x - 10) ** 2 + (y - 10) ** 2 + (z - 10) ** 2), order="xyz")
    cam = gc.Camera.look_at((10, -40, 10), (10, 10, 10))
    iso = gc.Renderer(W, H, background="white").render_isosurface(vol, 6.0, cam)
    assert iso.coverage.any() and (iso.image[~iso.coverage] == 255).all()
    # A translucent slice over nothing was blended with the core's black: it keeps that (documented).
    s = gc.Scene()
    s.add_slice(vol, "crossline", 10, cmap=[[0.2, 0.6, 1.0], [0.2, 0.6, 1.0]], opacity=0.5)
    side = gc.Camera.look_at((10, -60, 10), (10, 10, 10), projection="orthographic", ortho_height=40)
    white = gc.Renderer(W, H, background="white").render(s, side, culling="none")
    black = gc.Renderer(W, H, background="black").render(s, side, culling="none")
    lens = black.image[..., :3].any(axis=-1)
    assert lens.any() and not white.coverage.any()
    np.testing.assert_array_equal(white.image[lens], black.image[lens])
    assert (white.image[~lens] == 255).all()
