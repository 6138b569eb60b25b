"""culling="temporal": the last frame's visible tiles drawn first, then every other tile's box
tested against that image and drawn when it shows. Whatever the history (another view, another
scene, objects hidden or moved since), the image equals "none" with pixel_threshold 0, and with a
coherent camera it draws about what the oracle draws.

GEOCULL_CONSERVATIVE_EXAMPLES (default 300) sets the number of random scene x camera sequences.
"""

from __future__ import annotations

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import given  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import geocull as gc  # noqa: E402
from test_three_pass_conservative import PROPERTY, H, W, cameras, pit_scene, scenes, top_down  # noqa: E402


def test_temporal_is_registered():
    assert "temporal" in gc.CULLING_MODES


def test_first_frame_then_the_same_view_reuses_the_visible_set(renderer_small):
    """The pit scene from above: the first frame (no history) takes its first set from three_pass's
    prepass (whose proxy misses the pit; the box test finds it); the second repeats it and draws
    exactly the tiles seen, untested: the lower plane's tile through the pit, nothing hidden."""
    r = gc.Renderer(96, 96)  # a renderer of its own: no history from other tests
    s, top, low = pit_scene()
    cam = top_down()
    none = r.render(s, cam, culling="none")
    first = r.render(s, cam, culling="temporal", pixel_threshold=0)
    np.testing.assert_array_equal(first.image, none.image)
    assert first.stats["tiles_reused"] == 0 and first.stats["triangles_prepass"] > 0
    assert first.tile_drawn.sum() < s.n_tiles  # the hidden lower tiles are not drawn
    second = r.render(s, cam, culling="temporal", pixel_threshold=0)
    np.testing.assert_array_equal(second.image, none.image)
    np.testing.assert_array_equal(second.depth, none.depth)
    seen = none.tile_pixels > 0
    assert second.stats["tiles_reused"] == int(seen.sum())
    assert (first.stats["frame_repeated"], second.stats["frame_repeated"]) == (0, 1)
    assert second.stats["tiles_box_tested"] == 0
    np.testing.assert_array_equal(second.tile_drawn, seen)  # exactly the oracle's set
    obj = s.tile_table()["object"]
    assert second.tile_drawn[obj == low].sum() >= 1  # the lower plane's tile under the pit


def test_history_of_another_view_or_scene_is_only_a_guess(renderer_small):
    """Frames of another view, another scene and a hidden object in between: every frame still
    equals none, and the history resets when the geometry changes."""
    r = gc.Renderer(96, 96)
    s, top, low = pit_scene()
    r.render(s, top_down(30.0, 30.0), culling="temporal", pixel_threshold=0)
    cam = gc.Camera.look_at((-20.0, -30.0, 25.0), (20.0, 20.0, -20.0))
    res = r.render(s, cam, culling="temporal", pixel_threshold=0)
    np.testing.assert_array_equal(res.image, r.render(s, cam, culling="none").image)
    other, _, _ = pit_scene(pit_depth=-10.0)
    res = r.render(other, cam, culling="temporal", pixel_threshold=0)
    assert res.stats["tiles_reused"] == 0  # another scene's geometry: no history
    s.set_visible(top, False)
    res = r.render(s, cam, culling="temporal", pixel_threshold=0)
    np.testing.assert_array_equal(res.image, r.render(s, cam, culling="none").image)


def test_whatever_decides_a_pixel_ends_a_repeat():
    """A frame repeats the last one (its visible tiles drawn untested) only when nothing that decides
    which tile wins a pixel changed: each change below is a frame that tests again, and every frame,
    repeated or not, equals none's. A change of colour alone repeats."""
    r = gc.Renderer(96, 96)
    s, top, low = pit_scene()
    cam = top_down(20.0, 25.0)

    def frame(cam=cam, **kw):
        res = r.render(s, cam, culling="temporal", pixel_threshold=0, **kw)
        ref = r.render(s, cam, culling="none", **kw)
        np.testing.assert_array_equal(res.image, ref.image)
        np.testing.assert_array_equal(res.depth, ref.depth)
        return res.stats["frame_repeated"]

    frame()
    assert frame() == 1
    s.set_color(top, (0.9, 0.2, 0.2))
    assert frame() == 1
    for change in (lambda: s.translate(low, (0.0, 0.0, 30.0)), lambda: s.set_priority(low, 9),
                   lambda: s.set_visible(top, False), lambda: s.set_visible(top, True)):
        change()
        assert frame() == 0 and frame() == 1
    exaggerated = gc.Camera.look_at((20.0, 25.0, 40.0), (20.0, 25.0, 0.0), up=(0, 1, 0), fov_y=30.0, z_scale=3.0)
    for kw in (dict(cam=top_down(20.0, 25.5)), dict(cam=exaggerated),
               dict(cam=exaggerated, lod="screen_error", max_pixel_error=4.0)):
        assert frame(**kw) == 0 and frame(**kw) == 1
    # A threshold above 0 never repeats (its image is not none's).
    r.render(s, cam, culling="temporal", pixel_threshold=5)
    assert r.render(s, cam, culling="temporal", pixel_threshold=5).stats["frame_repeated"] == 0


def test_threshold_keeps_its_meaning():
    r = gc.Renderer(96, 96)
    s, _, _ = pit_scene()
    cam = top_down(10.0, 12.0)
    none = r.render(s, cam, culling="none")
    for t in (0, 3, 20):
        r.render(s, top_down(30.0, 30.0), culling="temporal", pixel_threshold=0)  # a history from elsewhere
        res = r.render(s, cam, culling="temporal", pixel_threshold=t)
        assert (res.tile_drawn | (none.tile_pixels <= t)).all(), t


@PROPERTY
@given(data=st.data())
def test_temporal_never_misses_a_visible_tile(renderer_small, data):
    """Random stacked rough horizons with faults, a random camera sequence (the history of each
    frame is the one before): every frame draws a superset of the oracle's tiles and equals none."""
    s, n = data.draw(scenes())
    r = renderer_small(W, H)
    for _ in range(data.draw(st.integers(1, 3))):
        cam = data.draw(cameras(n))
        res = r.render(s, cam, culling="temporal", pixel_threshold=0)
        oracle = r.render(s, cam, culling="oracle")
        none = r.render(s, cam, culling="none")
        assert (res.tile_drawn | ~oracle.tile_drawn).all(), "a visible tile was culled"
        np.testing.assert_array_equal(res.image, none.image)
        np.testing.assert_array_equal(res.depth, none.depth)
