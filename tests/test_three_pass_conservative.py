"""three_pass with conservative=True (the default) never culls a tile that has a visible pixel,
whatever the proxies, the prepass scale and the camera; with conservative=False and
predict_errors=True every tile the approximate mode misses is reported at risk.

GEOCULL_CONSERVATIVE_EXAMPLES (default 300) sets the number of random scenes x cameras.
"""

from __future__ import annotations

import os

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import geocull as gc  # noqa: E402

W, H = 48, 36
EXAMPLES = int(os.environ.get("GEOCULL_CONSERVATIVE_EXAMPLES", "300"))
PROPERTY = settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=not os.environ.get("GEOCULL_FUZZ_RANDOM"),
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)


def pit_scene(pit_depth: float = -100.0) -> tuple[gc.Scene, int, int]:
    """A 41 x 41 plane at z = 0 (4 x 4 tiles, lattice proxies at stride 5) with a 3 x 3-sample pit
    at samples 6..8 (between lattice samples, so the proxy does not see it) reaching down to
    ``pit_depth``, over a lower plane at z = -50: from above, the lower plane shows inside the pit."""
    z = np.zeros((41, 41))
    z[6:9, 6:9] = pit_depth
    s = gc.Scene()
    top = s.add_heightfield(z, origin=(0.0, 0.0), spacing=(1.0, 1.0), tiles=(4, 4), coarse_factor=25)
    low = s.add_heightfield(np.full((41, 41), -50.0), origin=(0.0, 0.0), spacing=(1.0, 1.0), tiles=(4, 4),
                            coarse_factor=25)
    return s, top, low


def top_down(x: float = 7.0, y: float = 7.0) -> gc.Camera:
    return gc.Camera.look_at((x, y, 40.0), (x, y, 0.0), up=(0, 1, 0), fov_y=30.0)


def test_pit_is_missed_by_the_approximate_mode_and_found_by_the_conservative_one(renderer_small):
    r = renderer_small(96, 96)
    s, top, low = pit_scene()
    cam = top_down()
    none = r.render(s, cam, culling="none")
    approx = r.render(s, cam, culling="three_pass", pixel_threshold=0, conservative=False, predict_errors=True)
    cons = r.render(s, cam, culling="three_pass", pixel_threshold=0)
    obj = s.tile_table()["object"]
    # By construction the lower plane shows through the pit, and its proxy-based count is 0.
    assert none.tile_pixels[obj == low].sum() > 0
    assert approx.tile_pixels[obj == low].sum() == 0
    assert not np.array_equal(approx.image, none.image), "the test scene must fool the approximate mode"
    # The predictor names every tile that was missed.
    missed = none.tile_drawn & (none.tile_pixels > 0) & ~approx.tile_drawn
    assert missed.any() and approx.tile_at_risk is not None
    assert (approx.tile_at_risk | ~missed).all()
    assert approx.stats["predicted_max_missing_pixels"] >= int((approx.image != none.image).any(axis=2).sum())
    # The conservative mode gives the unculled image.
    np.testing.assert_array_equal(cons.image, none.image)
    np.testing.assert_array_equal(cons.depth, none.depth)
    assert cons.stats["tiles_drawn_second"] >= 1
    assert cons.stats["triangles_drawn"] < none.stats["triangles_drawn"]


def test_threshold_keeps_its_meaning(renderer_small):
    """With conservative=True and threshold t, every tile with more than t visible pixels in the
    unculled image is drawn."""
    r = renderer_small(96, 96)
    s, _, _ = pit_scene()
    cam = top_down(10.0, 12.0)
    none = r.render(s, cam, culling="none")
    for t in (0, 3, 20):
        res = r.render(s, cam, culling="three_pass", pixel_threshold=t)
        assert (res.tile_drawn | (none.tile_pixels <= t)).all(), t


def test_conservative_is_the_default(renderer_small):
    r = renderer_small(48, 48)
    s, _, _ = pit_scene()
    res = r.render(s, top_down(), culling="three_pass")
    assert "tiles_drawn_second" in res.stats and res.box_pixels is not None


def test_default_prepass_scale_is_half_for_conservative_frames_and_one_for_the_paper(renderer_small):
    """prepass_scale=None: 0.5 when conservative (the image does not depend on it), 1 otherwise.
    tile_pixels are the prepass counts scaled to the image, so they show which prepass ran."""
    r = renderer_small(96, 96)
    s, _, _ = pit_scene()
    cam = gc.Camera.look_at((20.0, -25.0, 30.0), (20.0, 20.0, -20.0))
    px = {(c, ps): r.render(s, cam, culling="three_pass", pixel_threshold=0, conservative=c,
                            **({} if ps is None else dict(prepass_scale=ps))).tile_pixels
          for c in (True, False) for ps in (None, 0.5, 1.0)}
    assert not np.array_equal(px[True, 0.5], px[True, 1.0]), "the scene must tell the two scales apart"
    assert np.array_equal(px[True, None], px[True, 0.5])
    assert np.array_equal(px[False, None], px[False, 1.0])


def test_conservative_prepass_draws_each_tiles_cheapest_proxy(renderer_small):
    """Built without coarse proxies (coarse_factor 1: the proxy is the fine tile), the conservative
    prepass draws each tile's cheapest of its coarse proxy, its coarsest level of detail and, for a
    hole-free height-field tile, its occluder (corner, mid-side and centre samples: 8 triangles);
    the approximate mode, whose culling rests on the built proxies, still draws those. Same image."""
    rng = np.random.default_rng(3)
    s = gc.Scene()
    s.add_heightfield(rng.normal(0.0, 2.0, (41, 41)), tiles=(4, 4))  # coarse_factor 1
    s.add_heightfield(rng.normal(-30.0, 2.0, (41, 41)), tiles=(4, 4), coarse_factor=100)
    t = s.tile_table()
    levels = t["level_triangles"]
    coarsest = np.array([row[row > 0][-1] if (row > 0).any() else 0 for row in levels])
    cheapest = np.where((coarsest > 0) & (coarsest < t["tris_coarse"]), coarsest, t["tris_coarse"])
    fine_horizon = t["object"] == 0
    assert (cheapest[fine_horizon] > 8).all() and (cheapest[~fine_horizon] < 8).all(), "both cases must occur"
    cheapest = np.minimum(cheapest, 8)  # every tile here is a hole-free height-field tile of >= 3 x 3 samples
    r = renderer_small(64, 48)
    cam = gc.Camera.look_at((20.0, -30.0, 40.0), (20.0, 20.0, -10.0))
    none = r.render(s, cam, culling="none")
    cons = r.render(s, cam, culling="three_pass", pixel_threshold=0)
    approx = r.render(s, cam, culling="three_pass", pixel_threshold=0, conservative=False)
    assert cons.stats["triangles_prepass"] == cheapest.sum()
    assert approx.stats["triangles_prepass"] == t["tris_coarse"].sum()
    assert np.array_equal(cons.image, none.image)
    first = r.render(s, cam, culling="temporal", pixel_threshold=0)  # no history for this scene yet
    assert first.stats["tiles_reused"] == 0 and first.stats["triangles_prepass"] == cheapest.sum()


# ------------------------------------------------------------------ random scenes and cameras


@st.composite
def scenes(draw):
    """Stacked rough horizons (holes, nulls, thin layers, coincident ones) and faults."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    n = draw(st.sampled_from([9, 17, 25]))
    tiles = draw(st.sampled_from([(1, 1), (2, 3), (4, 4)]))
    cf = draw(st.sampled_from([4.0, 25.0, 100.0]))
    s = gc.Scene()
    gap = draw(st.sampled_from([0.0, 0.5, 3.0, 10.0]))
    for k in range(draw(st.integers(1, 3))):
        rough = draw(st.sampled_from([0.5, 3.0, 10.0]))
        z = rng.normal(scale=rough, size=(n, n)).cumsum(0) * 0.3 - k * gap
        if draw(st.booleans()):
            z[rng.random((n, n)) < 0.1] = np.nan
        if draw(st.booleans()):
            z[rng.integers(0, n), :] = -999.25
        s.add_heightfield(z, origin=(0.0, 0.0), spacing=(1.0, 1.0), tiles=tiles, coarse_factor=cf, null_value=-999.25)
    for _ in range(draw(st.integers(0, 2))):
        a = rng.uniform(0, n, size=2)
        b = rng.uniform(0, n, size=2)
        zs = sorted(rng.uniform(-25, 15, size=2))
        v = np.array([[a[0], a[1], zs[0]], [b[0], b[1], zs[0]], [b[0], b[1], zs[1]], [a[0], a[1], zs[1]]])
        s.add_mesh(v, np.array([[0, 1, 2], [0, 2, 3]]), kind="fault", coarse_factor=cf)
    return s, n


@st.composite
def cameras(draw, n):
    c = np.array([n / 2, n / 2, 0.0]) + np.array([draw(st.floats(-n / 2, n / 2)), draw(st.floats(-n / 2, n / 2)),
                                                 draw(st.floats(-20, 5))])
    elev = draw(st.sampled_from([-60.0, -10.0, 1.0, 3.0, 8.0, 30.0, 89.0]))  # below, grazing, above
    az = draw(st.floats(0, 360))
    dist = draw(st.sampled_from([0.5, 5.0, 2.0 * n, 6.0 * n]))  # inside the stack to far away
    e, a = np.radians(elev), np.radians(az)
    eye = c + dist * np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    projection = draw(st.sampled_from(["perspective", "perspective", "orthographic"]))
    z_scale = draw(st.sampled_from([1.0, 1.0, 4.0, 0.3]))
    return gc.Camera.look_at(eye, c, fov_y=50.0, projection=projection, z_scale=z_scale)


@PROPERTY
@given(data=st.data())
def test_conservative_never_misses_a_visible_tile(renderer_small, data):
    s, n = data.draw(scenes())
    cam = data.draw(cameras(n))
    scale = data.draw(st.sampled_from([1.0, 1.0, 0.5, 0.25]))
    r = renderer_small(W, H)
    none = r.render(s, cam, culling="none")
    oracle = r.render(s, cam, culling="oracle")
    cons = r.render(s, cam, culling="three_pass", pixel_threshold=0, prepass_scale=scale)
    assert (cons.tile_drawn | ~oracle.tile_drawn).all(), "a visible tile was culled"
    np.testing.assert_array_equal(cons.image, none.image)
    np.testing.assert_array_equal(cons.depth, none.depth)
    approx = r.render(s, cam, culling="three_pass", pixel_threshold=0, prepass_scale=scale, conservative=False,
                      predict_errors=True)
    missed = oracle.tile_drawn & ~approx.tile_drawn
    assert approx.tile_at_risk is not None
    assert (approx.tile_at_risk | ~missed).all(), "a missed tile was predicted safe"
