"""Reservoir grids in the scene: a box grid renders like its box, inactive cells are holes, the
level chosen per block follows grid_lod, three_pass culls a grid hidden behind a horizon,
level 0 matches PyVista's surface of the same cells as VTK hexahedra, and interior faces are left
out from outside."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import geocull as gc

W, H = 96, 72


def box_corners(nk: int, nj: int, ni: int, d: float = 10.0, throw: float = 0.0) -> np.ndarray:
    """Cells d metres wide, k = 0 at the top (z = 0), the columns i >= ni // 2 dropped by ``throw``
    (a vertical normal fault between columns ni // 2 - 1 and ni // 2)."""
    c = np.zeros((nk, nj, ni, 8, 3))
    for q in range(8):
        di, dj, dk = q & 1, (q >> 1) & 1, (q >> 2) & 1
        k, j, i = np.meshgrid(np.arange(nk), np.arange(nj), np.arange(ni), indexing="ij")
        c[..., q, 0] = (i + di) * d
        c[..., q, 1] = (j + dj) * d
        c[..., q, 2] = -(k + dk) * d - np.where(i >= ni // 2, throw, 0.0)
    return c


def cam() -> gc.Camera:
    return gc.Camera.look_at((120, -90, 70), (25, 30, -20), fov_y=40)


def test_a_box_grid_renders_like_its_box(renderer_small):
    s = gc.Scene()
    g = s.add_grid(box_corners(4, 6, 5), blocks=(2, 3), color=(1, 1, 1))
    box = gc.Scene()
    v = np.array([[x, y, z] for z in (-40, 0) for y in (0, 60) for x in (0, 50)], float)
    f = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],
         [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    box.add_mesh(v, f, color=(1, 1, 1))
    r = renderer_small(W, H)
    a, b = r.render(s, cam()), r.render(box, cam())
    np.testing.assert_array_equal(a.coverage, b.coverage)
    np.testing.assert_allclose(a.depth[a.coverage], b.depth[a.coverage], rtol=1e-5)
    lv = s.grid_levels(g)
    assert lv[0]["faces"] == 2 * (5 * 6 + 6 * 4 + 4 * 5)
    assert lv[0]["volume"] == pytest.approx(50 * 60 * 40)
    assert all(abs(x["volume_change"]) < 1e-9 for x in lv)


def test_an_inactive_cell_is_a_hole_with_six_faces():
    s = gc.Scene()
    active = np.ones((3, 3, 3), bool)
    active[1, 1, 1] = False
    full = s.grid_levels(s.add_grid(box_corners(3, 3, 3)))[0]["faces"]
    holed = s.grid_levels(s.add_grid(box_corners(3, 3, 3), active=active))[0]["faces"]
    assert holed == full + 6
    active[0, 1, 1] = False  # opens the hole to the top: its top face and the cell's walls go
    with pytest.raises(gc.InputError, match="^corners"):
        bad = box_corners(2, 2, 2)
        bad[0, 0, 0, 3, 2] = np.nan
        s.add_grid(bad)
    bad = box_corners(2, 2, 2)
    bad[0, 0, 0, 3, 2] = np.nan
    a = np.ones((2, 2, 2), bool)
    a[0, 0, 0] = False
    s.add_grid(bad, active=a)  # an inactive cell may hold anything
    for kw, arg in [(dict(blocks=(0, 4)), "blocks"), (dict(values=np.zeros((2, 2))), "values"),
                    (dict(active=np.ones((2, 2, 3), bool)), "active")]:
        with pytest.raises(gc.InputError, match=f"^{arg}"):
            s.add_grid(box_corners(2, 2, 2), **kw)


def test_grid_lod_modes_choose_levels_and_report_them(renderer_small):
    s = gc.Scene()
    s.add_grid(box_corners(2, 16, 16, d=10.0), blocks=(8, 8), values=np.random.default_rng(0).random((2, 16, 16)))
    r = renderer_small(W, H)
    near = gc.Camera.look_at((80, -60, 60), (80, 80, -10))
    far = gc.Camera.look_at((80, -20000, 8000), (80, 80, -10), fov_y=2)
    full = r.render(s, near, grid_lod="full").stats
    assert full["grid_cells_level0"] == 2 * 16 * 16 and full.get("grid_cells_level1", 0) == 0
    # Far away every block takes its coarsest level (3 for 8 x 8 blocks).
    d = r.render(s, far, grid_lod="distance", alpha=8, lam=3).stats
    assert d["grid_cells_level3"] == 2 * 4 and d["grid_cells_level0"] == 0
    with pytest.raises(gc.InputError, match="^alpha"):
        r.render(s, near, grid_lod="distance", alpha=20)
    with pytest.raises(gc.InputError, match="^grid_lod"):
        r.render(s, near, grid_lod="near")  # type: ignore[arg-type]


def test_a_grid_behind_a_horizon_is_culled_by_three_pass(renderer_small):
    s = gc.Scene()
    g = s.add_grid(box_corners(3, 8, 8), blocks=(4, 4))
    s.add_heightfield(np.full((21, 21), 5.0), origin=(-50, -50), spacing=(9, 9), tiles=(2, 2))
    top = gc.Camera.look_at((40, 40, 300), (40, 40, 0), up=(0, 1, 0))
    r = renderer_small(W, H)
    none = r.render(s, top, culling="none")
    tp = r.render(s, top, culling="three_pass", pixel_threshold=0)
    np.testing.assert_array_equal(tp.image, none.image)
    blocks = s.tile_table()["object"] == g
    assert not tp.tile_drawn[blocks].any()


def test_a_faulted_grid_matches_pyvista_hexahedra(renderer_small):
    pv = pytest.importorskip("pyvista")
    corners = box_corners(3, 4, 6, throw=4.0)
    s = gc.Scene()
    s.add_grid(corners, blocks=(3, 2), color=(1, 1, 1))
    ours = renderer_small(W, H).render(s, cam())
    # The same cells as VTK hexahedra (VTK's point order: the bottom face, then the top face, each
    # counter-clockwise): our corners (i + 2 j + 4 k) in VTK's order.
    order = [4, 5, 7, 6, 0, 1, 3, 2]
    pts = corners[..., order, :].reshape(-1, 3)
    n = len(pts) // 8
    cells = np.hstack([np.full((n, 1), 8), np.arange(8 * n).reshape(n, 8)]).ravel()
    ug = pv.UnstructuredGrid(cells, np.full(n, pv.CellType.HEXAHEDRON), pts)
    ref = gc.Scene()
    ref.add_mesh(ug, color=(1, 1, 1))  # its outer surface, triangulated (geocull's PyVista input path)
    vtk = gc.pyvista.reference_image(ref, cam(), W, H, near=ours.near, far=ours.far)
    assert gc.compare.coverage_agreement(ours.depth, vtk["depth"]) >= 0.99
    both = ours.coverage & np.isfinite(vtk["depth"])
    rel = np.abs(ours.depth[both] - vtk["depth"][both]) / vtk["depth"][both]
    assert np.median(rel) < 1e-3


def test_interior_faces_are_left_out_from_outside(renderer_small):
    """Faces between regions and of a cavity (an inactive cell enclosed by present cells) are drawn last
    and left out while the grid lies beyond the near plane: the image is that of the same cells
    without regions and hole; from inside the grid nothing is left out."""
    c = box_corners(5, 6, 6)
    region = np.zeros((5, 6, 6), np.int32)
    region[3:] = 1
    active = np.ones((5, 6, 6), bool)
    active[1, 2, 2] = False
    s = gc.Scene()
    g = s.add_grid(c, active=active, region=region, blocks=(3, 3), color=(1, 1, 1))
    plain = gc.Scene()
    plain.add_grid(c, blocks=(3, 3), color=(1, 1, 1))
    lv = s.grid_levels(g)[0]
    assert lv["interior_triangles"] == 2 * 36 * 2 + 6 * 2  # both regions' boundary faces, the cavity
    r = renderer_small(W, H)
    a, b = r.render(s, cam()), r.render(plain, cam())
    assert a.stats["grid_interior_triangles_skipped"] == lv["interior_triangles"]
    assert a.stats["triangles_drawn"] == lv["triangles"] - lv["interior_triangles"]
    np.testing.assert_array_equal(a.image, b.image)
    inside = gc.Camera.look_at((25, 25, -15), (60, 60, -15))
    assert r.render(s, inside).stats["grid_interior_triangles_skipped"] == 0


def test_grids_survive_pickling(renderer_small):
    s = gc.Scene()
    g = s.add_grid(box_corners(2, 4, 4, throw=3.0), values=np.arange(32.0).reshape(2, 4, 4), blocks=(2, 2))
    t = pickle.loads(pickle.dumps(s))
    assert t.grid_levels(g) == s.grid_levels(g)
    r = renderer_small(W, H)
    np.testing.assert_array_equal(r.render(s, cam(), grid_lod="screen_error").image,
                                  r.render(t, cam(), grid_lod="screen_error").image)
