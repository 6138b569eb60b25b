"""xtgeo objects as they are (issue 37): passed straight to the add functions and ``gc.Volume``,
their conventions translated, undefined values masked, keyword overrides winning.

What is checked:
- ``gc.io.from_xtgeo_cube`` turns xtgeo's undefined value (1e33, missing traces) into NaN: exactly
  the undefined samples, so a slice's colour range is the defined samples' range and no
  isosurface is built around the gap; ``gc.Volume(cube)`` is ``gc.Volume(**from_xtgeo_cube(cube))``
  (same samples, bounds) with the cube's inline / crossline numbers and sample depths;
- ``add_heightfield(surface)`` equals ``add_heightfield(**from_xtgeo_surface(surface))`` (the same
  triangles) and takes the surface's name; ``name=``, ``tiles=``, ``origin=`` given win;
- ``add_well(xtgeo.Well, log=...)`` from an RMS well file written in the test: stations at
  (x, y, -TVDSS), the log's -999 (undefined) as NaN, ``max_stations`` keeping first and last;
  ``from_xtgeo_well`` on an in-memory well with 1e33 and discrete-undefined samples;
- ``add_mesh(xtgeo.TriangulatedSurface)`` at z = -depth; ``add_grid(xtgeo.Grid, values=name |
  GridProperty, region=GridProperty)`` the same triangles as the arrays of ``from_xtgeo_grid``;
- errors: ``log=`` without a well, an unknown log, an unknown property are InputErrors naming the
  argument.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import geocull as gc

xtgeo = pytest.importorskip("xtgeo")
pd = pytest.importorskip("pandas")


def dome_cube(undefined: bool = True):
    ncol, nrow, nlay = 21, 17, 30
    i, j, k = np.meshgrid(np.arange(ncol), np.arange(nrow), np.arange(nlay), indexing="ij")
    depth = 2000.0 + 5.0 * k
    values = (depth - (2040.0 + 0.5 * ((i - 10) ** 2 + (j - 8) ** 2))).astype(np.float32)
    if undefined:
        values[3:6, 2:4, :] = xtgeo.UNDEF  # six missing traces
        values[15, 12, 20:] = xtgeo.UNDEF  # the end of one trace
    return xtgeo.Cube(ncol=ncol, nrow=nrow, nlay=nlay, xinc=12.5, yinc=25.0, zinc=5.0, xori=456_000.0,
                      yori=6_780_000.0, zori=2000.0, rotation=20.0, yflip=-1, values=values,
                      ilines=np.arange(300, 300 + 2 * ncol, 2), xlines=np.arange(1000, 1000 + nrow))


def test_cube_undefined_values_become_nan_and_cube_goes_in_directly():
    cube = dome_cube()
    raw = np.asarray(cube.values)
    assert (raw >= 1e30).sum() == 6 * 30 + 10
    kw = gc.io.from_xtgeo_cube(cube)
    nan = np.isnan(kw["values"])
    np.testing.assert_array_equal(nan, raw >= 1e30)  # exactly the undefined samples
    np.testing.assert_array_equal(kw["values"][~nan], raw[~nan])
    assert kw["values"].dtype == np.float32
    np.testing.assert_array_equal(kw["inlines"], np.arange(300, 342, 2))
    np.testing.assert_array_equal(kw["crosslines"], np.arange(1000, 1017))
    np.testing.assert_array_equal(kw["samples"], 2000.0 + 5.0 * np.arange(30))
    # A complete cube is not copied.
    full = dome_cube(undefined=False)
    assert np.shares_memory(gc.io.from_xtgeo_cube(full)["values"], np.asarray(full.values))

    vol = gc.Volume(cube)
    ref = gc.Volume(**kw)
    assert vol.shape == ref.shape == (30, 17, 21)
    assert vol.bounds == ref.bounds and vol.rotation == pytest.approx(20.0)
    np.testing.assert_array_equal(vol.inlines, cube.ilines)
    np.testing.assert_array_equal(vol.crosslines, cube.xlines)
    np.testing.assert_array_equal(vol.samples, 2000.0 + 5.0 * np.arange(30))
    s = gc.Scene()
    sl = s.add_slice(vol, "sample", 25)  # crosses the undefined traces
    defined = raw[raw < 1e30]
    assert s.object_info(sl)["clim"] == pytest.approx((float(defined.min()), float(defined.max())), rel=1e-6)
    # The dome's apex is where xtgeo puts node (10, 8), at z = -2040; no surface at the gaps' walls
    # reaches above it.
    v, f = gc.extract_isosurface(vol, 0.0)
    apex = v[np.argmax(v[:, 2])]
    x, y = cube.get_xy_value_from_ij(10, 8, zerobased=True)
    assert abs(apex[0] - x) < 1.0 and abs(apex[1] - y) < 1.0
    assert apex[2] == pytest.approx(-2040.0, abs=0.5)
    # keyword overrides win over the cube's own geometry
    moved = gc.Volume(cube, origin=(0.0, 0.0, 2000.0), rotation=0.0, yflip=False)
    assert moved.bounds[0][:2] == pytest.approx((0.0, 0.0))


def make_surface():
    ncol, nrow = 40, 30
    i, j = np.meshgrid(np.arange(ncol), np.arange(nrow), indexing="ij")
    depth = 1700.0 + 20.0 * np.sin(i / 7.0) + 0.5 * j
    values = np.ma.MaskedArray(depth, mask=(i - 20) ** 2 + (j - 10) ** 2 < 20)
    return xtgeo.RegularSurface(ncol=ncol, nrow=nrow, xinc=25.0, yinc=30.0, xori=461_000.0, yori=5_930_000.0,
                                rotation=30.0, yflip=-1, values=values, name="TopReek")


def test_surface_directly_equals_the_dict_and_keywords_win():
    surf = make_surface()
    a, b = gc.Scene(), gc.Scene()
    ia = a.add_heightfield(surf, tiles=(4, 3))
    ib = b.add_heightfield(**gc.io.from_xtgeo_surface(surf), tiles=(4, 3), name="TopReek")
    va, fa = a.geometry(ia)
    vb, fb = b.geometry(ib)
    np.testing.assert_array_equal(va, vb)
    np.testing.assert_array_equal(fa, fb)
    assert a.object_info(ia)["name"] == "TopReek" and a.object_info(ia)["n_tiles"] == 12
    assert -1800.0 < va[:, 2].min() < va[:, 2].max() < -1600.0  # z = -depth
    ic = a.add_heightfield(surf, name="Top", origin=(461_100.0, 5_930_000.0), z_positive="up")
    vc, _ = a.geometry(ic)
    assert a.object_info(ic)["name"] == "Top"
    assert vc[:, 2].min() > 1600.0  # "up": the stored depths as they are
    np.testing.assert_allclose(vc[:, :2].min(axis=0) - va[:, :2].min(axis=0), (100.0, 0.0), atol=1e-6)


def rms_well(tmp_path):
    """An RMS ascii well written by xtgeo: 60 stations down to 1800 m TVDSS, Poro with undefined
    (-999 in the file) every 7th station, a discrete Facies log."""
    n = 60
    z = np.linspace(0.0, 1800.0, n)
    poro = np.where(np.arange(n) % 7 == 0, np.nan, 0.2 + 0.001 * np.arange(n))
    df = pd.DataFrame({"X_UTME": 462_000.0 + 0.3 * z, "Y_UTMN": 5_933_000.0 - 0.1 * z, "Z_TVDSS": z,
                       "Poro": poro, "Facies": (np.arange(n) % 3).astype(float)})
    w = xtgeo.Well(rkb=0.0, xpos=462_000.0, ypos=5_933_000.0, wname="OP_9", df=df,
                   wlogtypes={"Poro": "CONT", "Facies": "DISC"},
                   wlogrecords={"Poro": "UNK", "Facies": {0: "a", 1: "b", 2: "c"}})
    path = tmp_path / "OP_9.w"
    w.to_file(path)
    assert "-999" in path.read_text()  # the undefined Poro samples as the file holds them
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return xtgeo.well_from_file(path), df


def test_well_from_an_rms_file(tmp_path):
    well, df = rms_well(tmp_path)
    kw = gc.io.from_xtgeo_well(well, log="Poro")
    assert set(kw) == {"path", "values"}
    np.testing.assert_allclose(kw["path"], np.c_[df["X_UTME"], df["Y_UTMN"], -df["Z_TVDSS"]], atol=1e-6)
    np.testing.assert_array_equal(np.isnan(kw["values"]), np.arange(60) % 7 == 0)
    np.testing.assert_allclose(kw["values"][1:7], 0.2 + 0.001 * np.arange(1, 7), atol=1e-9)
    assert gc.io.from_xtgeo_well(well)["values"] is None
    short = gc.io.from_xtgeo_well(well, log="Poro", max_stations=10)
    assert len(short["path"]) == 10
    np.testing.assert_array_equal(short["path"][[0, -1]], kw["path"][[0, -1]])  # first and last kept
    s = gc.Scene()
    wid = s.add_well(well, log="Poro", radius=5.0, max_stations=10)
    info = s.object_info(wid)
    assert info["name"] == "OP_9" and info["kind"] == "well"
    assert info["clim"] == pytest.approx((np.nanmin(short["values"]), np.nanmax(short["values"])))
    (lo, hi) = s.bounds
    assert -1805.0 < lo[2] < -1800.0 and 0.0 < hi[2] < 5.0  # stations at z = -TVDSS, the tube's radius about them
    # keywords win; the same tube as the dict gives
    other = gc.Scene()
    oid = other.add_well(**short, radius=5.0, name="mine")
    assert other.object_info(oid)["name"] == "mine"
    np.testing.assert_array_equal(other.geometry(oid)[0], s.geometry(wid)[0])
    with pytest.raises(gc.InputError, match="^log: the well 'OP_9' has no log 'Perm'"):
        s.add_well(well, log="Perm")
    with pytest.raises(gc.InputError, match="^log: only with an xtgeo Well"):
        s.add_well(kw["path"], log="Poro")
    with pytest.raises(gc.InputError, match="^max_stations"):
        gc.io.from_xtgeo_well(well, max_stations=1)


def test_well_undefined_values_in_memory():
    n = 8
    df = pd.DataFrame({"X_UTME": np.arange(n) * 1.0, "Y_UTMN": np.zeros(n), "Z_TVDSS": np.arange(n) * 10.0,
                       "Poro": [0.1, 1e33, 0.3, -1e33, 0.5, np.nan, 0.7, 0.8],
                       "Zone": [1, 1, 2, 2_000_000_000, 3, 3, 3, 3]})
    w = xtgeo.Well(rkb=0.0, xpos=0.0, ypos=0.0, wname="W", df=df, wlogtypes={"Poro": "CONT", "Zone": "DISC"},
                   wlogrecords={"Poro": "UNK", "Zone": {1: "A", 2: "B", 3: "C"}})
    poro = gc.io.from_xtgeo_well(w, log="Poro")["values"]
    np.testing.assert_array_equal(np.isnan(poro), [False, True, False, True, False, True, False, False])
    zone = gc.io.from_xtgeo_well(w, log="Zone", z_positive="up")
    np.testing.assert_array_equal(np.isnan(zone["values"]), [False] * 3 + [True] + [False] * 4)
    np.testing.assert_array_equal(zone["path"][:, 2], np.arange(n) * 10.0)  # "up": as stored


def test_triangulated_surface_goes_in_at_minus_depth():
    v = np.array([[0.0, 0.0, 1000.0], [100.0, 0.0, 1000.0], [0.0, 100.0, 1100.0], [100.0, 100.0, 1100.0]])
    t = np.array([[0, 1, 3], [0, 3, 2]])
    ts = xtgeo.TriangulatedSurface(vertices=v, triangles=t, name="F1")
    s = gc.Scene()
    mid = s.add_mesh(ts, kind="fault")
    verts, faces = s.geometry(mid)
    assert s.object_info(mid)["name"] == "F1"
    np.testing.assert_allclose(np.sort(verts[:, 2]), [-1100.0, -1100.0, -1000.0, -1000.0])
    # faces reversed under the mirror: each triangle's normal keeps its side of the surface (the
    # first triangle's (0, -1, 1) in (x, y, depth), pointing deeper, is (0, -1, -1) in (x, y, z))
    a, b, c = verts[faces[0, 0]], verts[faces[0, 1]], verts[faces[0, 2]]
    n = np.cross(b - a, c - a)
    np.testing.assert_allclose(n / np.linalg.norm(n), np.array([0.0, -1.0, -1.0]) / np.sqrt(2), atol=1e-12)
    up = s.add_mesh(ts, kind="fault", z_positive="up", name="F1 as elevation")
    assert s.geometry(up)[0][:, 2].min() == pytest.approx(1000.0)
    # arrays: "down" flips, default "up" keeps
    arr = s.add_mesh(v, t, z_positive="down")
    np.testing.assert_allclose(s.geometry(arr)[0][:, 2].max(), -1000.0)
    with pytest.raises(gc.InputError, match="^z_positive"):
        s.add_mesh(v, t, z_positive="Down")  # type: ignore[arg-type]


def test_grid_directly_with_values_and_region():
    grid = xtgeo.create_box_grid((6, 5, 3), increment=(50.0, 40.0, 5.0), origin=(461_000.0, 5_930_000.0, 1600.0),
                                 rotation=15.0)
    act = grid.get_actnum()
    act.values[0, 0, :] = 0
    grid.set_actnum(act)
    poro = xtgeo.GridProperty(grid, name="PORO", values=np.linspace(0.1, 0.3, 90).reshape(6, 5, 3))
    zone = xtgeo.GridProperty(grid, name="ZONE", discrete=True,
                              values=np.repeat(np.array([1, 1, 2])[None, None, :], 30, axis=0).reshape(6, 5, 3))
    grid.append_prop(poro)
    grid.append_prop(zone)
    kw = gc.io.from_xtgeo_grid(grid, "PORO")
    region = gc.io.xtgeo_property(zone, grid)
    assert np.nanmax(region) == 2.0 and np.isnan(region[:, 0, 0]).all()  # inactive cells
    s = gc.Scene()
    a = s.add_grid(grid, values="PORO", region=zone, blocks=(4, 4))
    b = s.add_grid(**kw, region=np.where(np.isfinite(region), region, -1).astype(np.int32), blocks=(4, 4),
                   name="same")
    c = s.add_grid(grid, values=poro, region="ZONE", blocks=(4, 4))
    va, fa = s.geometry(a)
    for other in (b, c):
        vo, fo = s.geometry(other)
        np.testing.assert_array_equal(va, vo)
        np.testing.assert_array_equal(fa, fo)
    assert s.object_info(a)["clim"] == pytest.approx((0.1 + 0.2 * 3 / 89, 0.3))  # the active cells' range
    assert -1616.0 < va[:, 2].min() < va[:, 2].max() < -1599.0  # z = -depth
    assert s.object_info(b)["name"] == "same"
    with pytest.raises(gc.InputError, match="^values: the grid has no property 'NOPE'"):
        s.add_grid(grid, values="NOPE")
    with pytest.raises(gc.InputError, match="^values: a property name"):
        s.add_grid(kw["corners"], values="PORO")
