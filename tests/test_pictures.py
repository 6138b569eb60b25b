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
