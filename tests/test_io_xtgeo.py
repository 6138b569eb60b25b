"""geocull.io with real xtgeo objects (issue 16 acceptance): surfaces, cubes and grids.

What is checked:
- an xtgeo RegularSurface rotated 30° with an undefined hole, written to IRAP binary and read back,
  goes in with ``add_heightfield(**gc.io.from_xtgeo_surface(surf))`` and renders the same coverage
  (>= 99 %, ``gc.compare.coverage_agreement``) as the surface triangulated by PyVista from
  ``surf.get_xyz_values()`` (rendered by VTK, ``gc.pyvista.reference_image``, and by geocull from the
  PolyData given to ``add_mesh``); yflip=-1 surfaces too; every culling mode gives the unculled
  image of it; z = -depth; undefined values (masked, or 1e33 left unmasked) are holes;
- an xtgeo Cube (rotated, yflip -1 and 1) holding a dome: ``gc.Volume(**gc.io.from_xtgeo_cube(cube))``
  puts the dome's apex at the position xtgeo gives for its node (``get_xy_value_from_ij``), at
  z = -(apex depth);
- an xtgeo Grid: ``from_xtgeo_grid`` corners follow the documented order (corner c: i-bit c & 1,
  j-bit (c >> 1) & 1, k-bit (c >> 2) & 1, k = 0 the top) against ``get_xyz_cell_corners``; active
  cells and properties by name or object, inactive / masked as NaN.
"""

from __future__ import annotations

import numpy as np
import pytest

import geocull as gc

xtgeo = pytest.importorskip("xtgeo")

W, H = 160, 120


@pytest.fixture(scope="module")
def renderer() -> gc.Renderer:
    return gc.Renderer(W, H)


def make_surface(rotation: float = 30.0, yflip: int = 1) -> object:
    ncol, nrow = 60, 45
    i, j = np.meshgrid(np.arange(ncol), np.arange(nrow), indexing="ij")  # xtgeo stores (ncol, nrow)
    depth = 1700.0 + 40.0 * np.sin(i / 9.0) * np.cos(j / 7.0) + 0.5 * i
    values = np.ma.MaskedArray(depth, mask=(i - 35) ** 2 + (j - 20) ** 2 < 40)  # an undefined hole
    return xtgeo.RegularSurface(ncol=ncol, nrow=nrow, xinc=25.0, yinc=30.0, xori=461_000.0, yori=5_930_000.0,
                                rotation=rotation, yflip=yflip, values=values, name="TopVolantis")


def irap_roundtrip(surf, tmp_path):
    path = tmp_path / "top.gri"
    surf.to_file(path, fformat="irap_binary")
    return xtgeo.surface_from_file(path, fformat="irap_binary")


def xyz_polydata(surf):
    """The surface triangulated by PyVista from get_xyz_values(): a quad per cell whose 4 nodes are
    defined, triangulated by PyVista; z = -depth."""
    pv = pytest.importorskip("pyvista")
    x, y, z = surf.get_xyz_values()
    ok = ~np.ma.getmaskarray(z)
    ncol, nrow = z.shape
    pts = np.stack([np.ma.getdata(a).ravel() for a in (x, y, z)], axis=1) * (1.0, 1.0, -1.0)
    pts[~ok.ravel()] = 0.0  # undefined nodes are referenced by no cell
    ii, jj = np.meshgrid(np.arange(ncol - 1), np.arange(nrow - 1), indexing="ij")
    a = ii * nrow + jj  # node (i, j) is row-major index i*nrow + j of the (ncol, nrow) arrays
    quads = np.stack([a, a + nrow, a + nrow + 1, a + 1], axis=-1).reshape(-1, 4)
    quads = quads[ok.ravel()[quads].all(axis=1)]
    cells = np.hstack([np.full((len(quads), 1), 4), quads]).ravel()
    return pv.PolyData(pts, faces=cells).triangulate()


def top_view(scene: gc.Scene) -> gc.Camera:
    (x0, y0, _), (x1, y1, _) = scene.bounds
    c = ((x0 + x1) / 2, (y0 + y1) / 2)
    return gc.Camera.look_at((*c, 0.0), (*c, -2000.0), up=(0, 1, 0), projection="orthographic",
                             ortho_height=1.1 * max(y1 - y0, (x1 - x0) * H / W))


@pytest.mark.parametrize("yflip", [1, -1])
def test_rotated_irap_surface_matches_pyvista_triangulation(renderer, tmp_path, yflip):
    surf = irap_roundtrip(make_surface(30.0, yflip), tmp_path)
    assert surf.rotation == pytest.approx(30.0) and surf.yflip == yflip
    assert np.ma.getmaskarray(surf.values).sum() > 20, "the hole survives the IRAP round trip"
    kw = gc.io.from_xtgeo_surface(surf)
    assert kw["rotation"] == pytest.approx(30.0) and kw["yflip"] == (yflip == -1)
    # The dict holds geometry only (so that `**kw, name=...` works); the surface's own name comes
    # with the object itself: "TopVolantis" is lost in the IRAP file.
    assert "name" not in kw
    named = gc.Scene()
    assert named.object_info(named.add_heightfield(make_surface()))["name"] == "TopVolantis"
    assert named.object_info(named.add_heightfield(surf))["name"] not in ("unknown", "TopVolantis")  # no placeholder
    assert named.object_info(named.add_heightfield(make_surface(), name="Top"))["name"] == "Top"  # keywords win
    assert named.object_info(named.add_heightfield(**kw, name="Top", tiles=(2, 2)))["name"] == "Top"
    assert kw["z"].shape == (surf.nrow, surf.ncol)
    s = gc.Scene()
    sid = s.add_heightfield(**kw, tiles=(6, 5))
    ref = gc.Scene()
    ref.add_mesh(xyz_polydata(surf))  # a PolyData straight into add_mesh
    (lo, hi), (rlo, rhi) = s.bounds, ref.bounds
    np.testing.assert_allclose(lo, rlo, atol=0.01)
    np.testing.assert_allclose(hi, rhi, atol=0.01)
    assert -1800.0 < lo[2] < hi[2] < -1650.0  # z = -depth
    cam = top_view(s)
    ours = renderer.render(s, cam)
    mesh = renderer.render(ref, cam)
    assert ours.coverage.mean() > 0.3
    assert gc.compare.coverage_agreement(ours.depth, mesh.depth) >= 0.99
    vtk = gc.pyvista.reference_image(ref, cam, W, H, near=ours.near, far=ours.far)
    assert gc.compare.coverage_agreement(ours.depth, vtk["depth"]) >= 0.99
    # culling works on it as on any height field
    low = gc.Camera.look_at((lo[0] - 300.0, lo[1] - 300.0, hi[2] + 150.0), s.bounds[1], fov_y=50.0)
    for cam in (top_view(s), low):
        none = renderer.render(s, cam, culling="none")
        for mode in gc.CULLING_MODES:
            res = renderer.render(s, cam, culling=mode, pixel_threshold=0)
            np.testing.assert_array_equal(res.image, none.image, err_msg=mode)
    assert s.object_info(sid)["n_triangles"] == ref.n_triangles + np.count_nonzero(
        _three_defined_cells(surf)
    )


def _three_defined_cells(surf):
    """Cells with exactly three defined nodes: one of their triangles is drawn by the height field
    (a triangle needs its own three nodes), none by the quad triangulation above."""
    ok = ~np.ma.getmaskarray(surf.values)
    n = ok[:-1, :-1].astype(int) + ok[1:, :-1] + ok[:-1, 1:] + ok[1:, 1:]
    a, b, c, d = ok[:-1, :-1], ok[1:, :-1], ok[:-1, 1:], ok[1:, 1:]  # (i,j), (i+1,j), (i,j+1), (i+1,j+1)
    # the height field's triangles (i,j)-(i+1,j)-(i+1,j+1) and (i,j)-(i+1,j+1)-(i,j+1)
    return (n == 3) & ((a & b & d) | (a & d & c))


def test_undefined_values_are_holes_and_z_positive():
    surf = make_surface(0.0)
    v = surf.values.copy()
    data = np.ma.getdata(v).copy()
    data[5, 5] = xtgeo.UNDEF  # an undefined value left unmasked
    kw = gc.io.from_xtgeo_surface(xtgeo.RegularSurface(ncol=60, nrow=45, xinc=25.0, yinc=30.0, values=data))
    assert kw["z"].mask[5, 5] and kw["z"].mask.sum() == 1
    up = gc.io.from_xtgeo_surface(surf, z_positive="up")
    np.testing.assert_array_equal(up["z"], -gc.io.from_xtgeo_surface(surf)["z"])
    s = gc.Scene()
    s.add_heightfield(**kw)
    assert s.n_triangles == 2 * 59 * 44 - 6
    with pytest.raises(gc.InputError, match="z_positive"):
        gc.io.from_xtgeo_surface(surf, z_positive="Down")  # type: ignore[arg-type]


def dome_cube(rotation: float, yflip: int):
    ncol, nrow, nlay = 31, 25, 40
    i, j, k = np.meshgrid(np.arange(ncol), np.arange(nrow), np.arange(nlay), indexing="ij")
    depth = 2000.0 + 5.0 * k
    apex_depth = 2030.0 + 0.6 * ((i - 18) ** 2 + (j - 9) ** 2)  # apex at node (18, 9)
    values = (depth - apex_depth).astype(np.float32)
    return xtgeo.Cube(ncol=ncol, nrow=nrow, nlay=nlay, xinc=12.5, yinc=25.0, zinc=5.0, xori=456_000.0,
                      yori=6_780_000.0, zori=2000.0, rotation=rotation, yflip=yflip, values=values)


@pytest.mark.parametrize("rotation,yflip", [(0.0, 1), (37.0, 1), (-20.0, -1), (90.0, -1)])
def test_cube_dome_apex_where_xtgeo_puts_it(rotation, yflip):
    cube = dome_cube(rotation, yflip)
    kw = gc.io.from_xtgeo_cube(cube)
    assert kw["order"] == "xyz" and kw["z_positive"] == "down"
    vol = gc.Volume(**kw)
    v, f = gc.extract_isosurface(vol, 0.0)
    assert len(f) > 100
    apex = v[np.argmax(v[:, 2])]
    x, y = cube.get_xy_value_from_ij(18, 9, zerobased=True)
    assert abs(apex[0] - x) < 1.0 and abs(apex[1] - y) < 1.0, (apex, (x, y))
    assert apex[2] == pytest.approx(-2030.0, abs=0.5)
    corner = cube.get_xy_value_from_ij(30, 24, zerobased=True)
    lo, hi = vol.bounds
    assert lo[0] - 1e-6 <= corner[0] <= hi[0] + 1e-6 and lo[1] - 1e-6 <= corner[1] <= hi[1] + 1e-6


def test_grid_corners_active_and_properties():
    grid = xtgeo.create_box_grid((3, 2, 2), increment=(10.0, 20.0, 5.0), origin=(100.0, 200.0, 1000.0),
                                 rotation=30.0)
    act = grid.get_actnum()
    act.values[2, 1, 0] = 0
    grid.set_actnum(act)
    poro = xtgeo.GridProperty(grid, name="PORO", values=np.arange(12, dtype=np.float64).reshape(3, 2, 2) / 100)
    grid.append_prop(poro)
    out = gc.io.from_xtgeo_grid(grid, "PORO")
    assert out.keys() == gc.grid.from_xtgeo(grid, "PORO").keys() == {"corners", "active", "values"}  # add_grid's
    corners, active = out["corners"], out["active"]
    assert corners.shape == (2, 2, 3, 8, 3) and active.shape == (2, 2, 3)
    assert not active[0, 1, 2] and active.sum() == 11
    for k in range(2):
        for j in range(2):
            for i in range(3):
                xyz = np.array(grid.get_xyz_cell_corners((i + 1, j + 1, k + 1), activeonly=False)).reshape(8, 3)
                np.testing.assert_allclose(corners[k, j, i], xyz * (1, 1, -1), atol=1e-9)
    c = corners[0, 0, 0]
    t = np.radians(30.0)
    np.testing.assert_allclose(c[1] - c[0], (10 * np.cos(t), 10 * np.sin(t), 0), atol=1e-9)  # bit 0: i
    np.testing.assert_allclose(c[2] - c[0], (-20 * np.sin(t), 20 * np.cos(t), 0), atol=1e-9)  # bit 1: j
    np.testing.assert_allclose(c[4] - c[0], (0, 0, -5), atol=1e-9)  # bit 2: k, downwards from the top
    p = out["values"]
    assert p.shape == (2, 2, 3) and p[1, 0, 2] == pytest.approx(poro.values[2, 0, 1])
    assert np.isnan(p[0, 1, 2])  # inactive: masked in xtgeo -> NaN
    np.testing.assert_array_equal(gc.io.from_xtgeo_grid(grid, values=poro)["values"], p)
    np.testing.assert_array_equal(gc.io.xtgeo_property("PORO", grid), p)
    assert gc.io.from_xtgeo_grid(grid)["values"] is None
    with pytest.raises(gc.InputError, match="^values: the grid has no property 'NOPE'"):
        gc.io.from_xtgeo_grid(grid, "NOPE")
