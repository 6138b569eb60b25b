"""culling="frustum": CPU view-frustum culling of tile boxes. Exact by construction (the image
equals "none"), and it culls exactly the tiles whose boxes are outside the view."""

from __future__ import annotations

import numpy as np
import pytest

import geocull as gc


def plane(scene: gc.Scene, z: float = 0.0, n: int = 41, size: float = 100.0, tiles: int = 4) -> int:
    """An n x n sample plane of size x size metres centred on the origin, tiles x tiles tiles."""
    d = size / (n - 1)
    return scene.add_heightfield(
        np.full((n, n), z), origin=(-size / 2, -size / 2), spacing=(d, d), tiles=(tiles, tiles)
    )


@pytest.fixture(scope="module")
def renderer() -> gc.Renderer:
    return gc.Renderer(96, 72)


def test_frustum_is_registered():
    assert "frustum" in gc.CULLING_MODES


def test_top_down_narrow_view_draws_only_the_tile_below(renderer):
    s = gc.Scene()
    plane(s)  # tiles of 25 m; tile (1, 1) spans x, y in [-25, 0]
    cam = gc.Camera.look_at((-12.5, -12.5, 50.0), (-12.5, -12.5, 0.0), up=(0, 1, 0), fov_y=10.0)
    res = renderer.render(s, cam, culling="frustum")
    ref = renderer.render(s, cam, culling="none")
    t = s.tile_table()
    drawn = t[res.tile_drawn]
    assert len(drawn) == 1 and (drawn["ix"][0], drawn["iy"][0]) == (1, 1)
    assert res.stats["tiles_outside"] == s.n_tiles - 1
    np.testing.assert_array_equal(res.image, ref.image)
    np.testing.assert_array_equal(res.depth, ref.depth)


def test_objects_behind_the_eye_are_culled(renderer):
    s = gc.Scene()
    front = plane(s, z=0.0, tiles=2)
    behind = s.add_mesh(np.array([[0, 0, 80.0], [1, 0, 80], [0, 1, 80]]), np.array([[0, 1, 2]]))
    cam = gc.Camera.look_at((0.0, 0.0, 60.0), (0.0, 0.0, 0.0), up=(0, 1, 0))
    res = renderer.render(s, cam, culling="frustum")
    obj = s.tile_table()["object"]
    assert res.tile_drawn[obj == front].all()
    assert not res.tile_drawn[obj == behind].any()
    np.testing.assert_array_equal(res.image, renderer.render(s, cam, culling="none").image)


@pytest.mark.parametrize("eye", [(-40.0, -40.0, 3.0), (60.0, 0.0, 20.0), (0.0, 0.0, 0.5)])
@pytest.mark.parametrize("projection", ["perspective", "orthographic"])
def test_never_culls_a_visible_tile(renderer, eye, projection):
    """Low, grazing and inside views of translated, exaggerated planes: frustum draws a superset
    of the oracle's tiles and the image equals none."""
    s = gc.Scene()
    plane(s, z=-5.0, tiles=5)
    upper = plane(s, z=0.0, n=21, size=60.0, tiles=3)
    s.translate(upper, (10.0, -5.0, 2.0))
    cam = gc.Camera.look_at(eye, (10.0, 5.0, -2.0), projection=projection, z_scale=2.0)
    res = renderer.render(s, cam, culling="frustum")
    oracle = renderer.render(s, cam, culling="oracle")
    ref = renderer.render(s, cam, culling="none")
    assert (res.tile_drawn | ~oracle.tile_drawn).all(), "a visible tile was culled"
    np.testing.assert_array_equal(res.image, ref.image)
    np.testing.assert_array_equal(res.depth, ref.depth)
