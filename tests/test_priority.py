"""Depth ties: of two coincident surfaces the one of higher priority is seen (``priority=`` on
every ``add_*``, default by kind: horizons over faults over grids over slices), without speckle
and the same in every culling mode as in ``culling="none"``, whatever the draw order."""

from __future__ import annotations

import numpy as np
import pytest
from tests.test_grid import box_corners

import geocull as gc

W, H = 96, 72
RED, BLUE = (1.0, 0.0, 0.0), (0.0, 0.0, 1.0)


def cam() -> gc.Camera:
    return gc.Camera.look_at((30, -60, 45), (30, 30, 0), fov_y=45)


def plane_mesh(n: int = 7, size: float = 60.0) -> tuple[np.ndarray, np.ndarray]:
    """A flat square at z = 0 triangulated along the other diagonal than a height field's."""
    x = np.linspace(0, size, n)
    X, Y = np.meshgrid(x, x)
    v = np.stack([X.ravel(), Y.ravel(), np.zeros(n * n)], axis=1)
    f = []
    for j in range(n - 1):
        for i in range(n - 1):
            a, b, c, d = j * n + i, j * n + i + 1, (j + 1) * n + i, (j + 1) * n + i + 1
            f += [[a, b, c], [b, d, c]]
    return v, np.array(f)


def two_planes(mesh_priority: int | None = None) -> gc.Scene:
    s = gc.Scene()
    s.add_heightfield(np.zeros((13, 13)), spacing=(5, 5), tiles=(2, 2), color=RED)
    v, f = plane_mesh()
    s.add_mesh(v, f, tiles=3, color=BLUE, priority=mesh_priority)
    return s


def reds_and_blues(res: gc.RenderResult) -> tuple[int, int]:
    px = res.image[res.coverage][:, :3].astype(int)
    return int((px[:, 0] > px[:, 2]).sum()), int((px[:, 2] > px[:, 0]).sum())


@pytest.mark.parametrize("culling", gc.CULLING_MODES)
def test_two_coincident_planes_draw_the_higher_priority_in_every_mode(renderer_small, culling):
    r = renderer_small(W, H)
    for mesh_priority, winner in [(None, "red"), (9, "blue")]:
        s = two_planes(mesh_priority)
        none = r.render(s, cam(), culling="none")
        red, blue = reds_and_blues(none)
        # No speckle: every covered pixel shows the winner.
        assert (red, blue) == ((red + blue, 0) if winner == "red" else (0, red + blue)), (mesh_priority, red, blue)
        assert red + blue > W * H // 8
        res = r.render(s, cam(), culling=culling)
        np.testing.assert_array_equal(res.image, none.image, err_msg=f"{culling}, mesh priority {mesh_priority}")


def test_a_grid_top_on_its_horizon_shows_the_horizon(renderer_small):
    # The grid's top is the horizon it was built from (z = 0 over the same area).
    s = gc.Scene()
    g = s.add_grid(box_corners(2, 6, 6), blocks=(3, 3), color=BLUE)
    h = s.add_heightfield(np.zeros((7, 7)), spacing=(10, 10), color=RED)
    top = gc.Camera.look_at((30, 30, 200), (30, 30, 0), up=(0, 1, 0), fov_y=30)
    r = renderer_small(W, H)
    red, blue = reds_and_blues(r.render(s, top))
    assert blue == 0 and red > 0
    assert s.object_info(h)["priority"] == 4 and s.object_info(g)["priority"] == 2
    s.set_priority(g, 10)
    red, blue = reds_and_blues(r.render(s, top))
    assert red == 0 and blue > 0
    s.set_priority(g, None)
    assert s.object_info(g)["priority"] == 2


def test_a_bad_priority_is_named_and_adds_nothing():
    s = gc.Scene()
    for bad, err in [(16, gc.InputError), (-1, gc.InputError), ("high", gc.InputError)]:
        with pytest.raises(err, match="^priority"):
            s.add_heightfield(np.zeros((3, 3)), priority=bad)  # type: ignore[arg-type]
    assert s.object_ids() == []
    i = s.add_heightfield(np.zeros((3, 3)))
    with pytest.raises(gc.InputError, match="^priority"):
        s.set_priority(i, 99)


def test_priorities_survive_pickling():
    import pickle

    s = two_planes(9)
    t = pickle.loads(pickle.dumps(s))
    assert [t.object_info(i)["priority"] for i in t.object_ids()] == [4, 9]
