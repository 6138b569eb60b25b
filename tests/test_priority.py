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


def test_every_kind_has_its_registered_default_priority():
    # the registry (src/scene/kinds.rs), one object of each kind through the Python API; a mesh
    # given a label of its user's behaves as "mesh"
    s = gc.Scene()
    v, f = plane_mesh()
    vals = np.linspace(0.0, 1.0, 9 * 9 * 9, dtype=np.float32).reshape(9, 9, 9)
    ball = np.fromfunction(lambda k, j, i: np.sqrt((i - 4) ** 2 + (j - 4) ** 2 + (k - 4) ** 2) - 2.5, (9, 9, 9))
    vol = gc.Volume(vals, origin=(0, 0, -80), spacing=(5, 5, 5))
    ids = {
        "heightfield": s.add_heightfield(np.zeros((13, 13)), spacing=(5, 5), tiles=(2, 2)),
        "fault": s.add_mesh(v, f, kind="fault"),
        "salt body": s.add_mesh(v, f, kind="salt body"),
        "well": s.add_well([[10, 10, 0], [10, 10, -50], [20, 15, -90]], radius=2.0),
        "grid": s.add_grid(box_corners(3, 2, 2)),
        "slice": s.add_slice(vol, axis="inline", index=4),
        "lens": s.add_lens(vol, ((1, 6), (1, 6), (1, 6))),
        "isosurface": s.add_isosurface(gc.Volume(ball.astype(np.float32), spacing=(5, 5, 5)), 0.0),
    }
    expected = {"well": 5, "heightfield": 4, "fault": 3, "salt body": 3, "isosurface": 3, "grid": 2, "slice": 1,
                "lens": 0}
    got = {k: (s.object_info(i)["kind"], s.object_info(i)["priority"]) for k, i in ids.items()}
    assert got == {k: (k, p) for k, p in expected.items()}
