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
    prepass (whose proxy misses the pit; the box test finds it); the second draws first exactly
    the tiles seen, tests the others, finds the lower plane's tile through the pit, and draws
    nothing hidden."""
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
