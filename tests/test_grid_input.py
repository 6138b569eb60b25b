"""Reservoir-grid input (issue 11): ``geocull.grid.from_grdecl`` / ``from_xtgeo`` and
``geocull.data.faulted_grid``.

What is checked:
- from_grdecl on a 2 x 2 x 2 grid built by hand (slanted pillars, a fault: column i = 1 thrown
  3 m) gives the corners computed independently, cell by cell, in the documented order, z = -depth;
- the same COORD / ZCORN / ACTNUM written as a GRDECL file and read by xtgeo give the same
  corners and active cells through from_xtgeo; an xtgeo box grid (rotated) written by xtgeo to
  GRDECL and read back as numbers agrees with from_xtgeo too; a property becomes ``values``;
- faulted_grid: shapes and dtypes, the fault's throw on the shared pillars, collapsed corners in
  the pinch-out (and fully collapsed cells inactive), the erosion truncating top layers, two or
  more regions, a property NaN exactly in the inactive cells.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import geocull as gc
from geocull import grid as gcgrid  # not among gc's lazy submodules (yet): imported directly


def hand_grid() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """COORD, ZCORN, ACTNUM of a 2 x 2 x 2 grid and its corners computed corner by corner."""
    nx = ny = nz = 2

    def depth(i: int, j: int, k: int, col_i: int) -> float:
        return 1000.0 + 5.0 * k + 1.0 * i + 2.0 * j + (3.0 if col_i == 1 else 0.0)

    coord = []
    for j in range(ny + 1):
        for i in range(nx + 1):
            coord += [10.0 * i, 10.0 * j, 1000.0, 10.0 * i + 5.0, 10.0 * j + 2.0, 1100.0]
    zcorn = []
    for k in range(nz):
        for kb in range(2):
            for j in range(ny):
                for jb in range(2):
                    for i in range(nx):
                        for ib in range(2):
                            zcorn.append(depth(i + ib, j + jb, k + kb, i))
    actnum = np.ones(nx * ny * nz, dtype=int)
    actnum[1 * nx * ny + 1 * nx + 0] = 0  # cell (k, j, i) = (1, 1, 0)
    want = np.empty((nz, ny, nx, 8, 3))
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                for c in range(8):
                    ib, jb, kb = c & 1, (c >> 1) & 1, (c >> 2) & 1
                    d = depth(i + ib, j + jb, k + kb, i)
                    t = (d - 1000.0) / 100.0
                    want[k, j, i, c] = [10.0 * (i + ib) + 5.0 * t, 10.0 * (j + jb) + 2.0 * t, -d]
    return np.array(coord), np.array(zcorn), actnum, want


def test_from_grdecl_by_hand() -> None:
    coord, zcorn, actnum, want = hand_grid()
    g = gcgrid.from_grdecl(coord, zcorn, actnum, nx=2, ny=2)
    assert g["corners"].shape == (2, 2, 2, 8, 3) and g["corners"].dtype == np.float64
    np.testing.assert_allclose(g["corners"], want, rtol=0, atol=1e-9)
    assert g["active"].shape == (2, 2, 2) and g["active"].dtype == bool
    assert not g["active"][1, 1, 0] and g["active"].sum() == 7
    # The fault: cells (k, j, 0) and (k, j, 1) share pillar i = 1 at depths 3 m apart.
    assert g["corners"][0, 0, 1, 0, 2] - g["corners"][0, 0, 0, 1, 2] == pytest.approx(-3.0)
    up = gcgrid.from_grdecl(coord.reshape(-1, 6), zcorn, None, nx=2, ny=2, nz=2, z_positive="up")
    np.testing.assert_allclose(up["corners"][..., 2], -want[..., 2])
    assert up["active"].all()
    with pytest.raises(gc.InputError, match="^coord"):
        gcgrid.from_grdecl(coord[:-1], zcorn, nx=2, ny=2)
    with pytest.raises(gc.InputError, match="^zcorn"):
        gcgrid.from_grdecl(coord, zcorn[:-3], nx=2, ny=2)
    with pytest.raises(gc.InputError, match="^actnum"):
        gcgrid.from_grdecl(coord, zcorn, actnum[:3], nx=2, ny=2)


def write_grdecl(
    path: Path, nx: int, ny: int, nz: int, coord: np.ndarray, zcorn: np.ndarray, actnum: np.ndarray
) -> None:
    def block(name: str, values: np.ndarray, fmt: str) -> str:
        body = "\n".join(" ".join(fmt % v for v in values[n : n + 6]) for n in range(0, len(values), 6))
        return f"{name}\n{body}\n/\n"

    path.write_text(
        f"SPECGRID\n {nx} {ny} {nz} 1 F /\n"
        + block("COORD", coord, "%.6f")
        + block("ZCORN", zcorn, "%.6f")
        + block("ACTNUM", actnum, "%d")
    )


def read_grdecl(path: Path, keys: tuple[str, ...] = ("COORD", "ZCORN", "ACTNUM")) -> dict[str, np.ndarray]:
    """The numeric keywords ``keys`` of a GRDECL file (``n*v`` repeats expanded)."""
    out: dict[str, list[float]] = {}
    key = None
    for line in path.read_text().splitlines():
        line = line.split("--", 1)[0].strip()
        if not line:
            continue
        if key is None:
            if line[0].isalpha():
                key = line.split()[0]
                out[key] = []
            continue
        for tok in line.replace("/", " / ").split():
            if tok == "/":
                key = None
                break
            if key not in keys:
                continue
            if "*" in tok:
                n, v = tok.split("*")
                out[key] += [float(v)] * int(n)
            else:
                out[key].append(float(tok))
    return {k: np.array(v) for k, v in out.items() if k in keys}


def test_from_xtgeo_agrees_with_from_grdecl(tmp_path: Path) -> None:
    xtgeo = pytest.importorskip("xtgeo")
    coord, zcorn, actnum, want = hand_grid()
    path = tmp_path / "hand.grdecl"
    write_grdecl(path, 2, 2, 2, coord, zcorn, actnum)
    grid = xtgeo.grid_from_file(path, fformat="grdecl")
    x = gcgrid.from_xtgeo(grid)
    np.testing.assert_allclose(x["corners"], want, rtol=0, atol=1e-4)
    np.testing.assert_array_equal(x["active"], gcgrid.from_grdecl(coord, zcorn, actnum, nx=2, ny=2)["active"])
    assert x["values"] is None

    # An xtgeo box grid (rotated) written by xtgeo, read back as numbers.
    box = xtgeo.create_box_grid((4, 3, 2), origin=(1000.0, 2000.0, 1500.0), increment=(50.0, 40.0, 5.0), rotation=30.0)
    poro = xtgeo.GridProperty(box, name="PORO", values=np.arange(24, dtype=float).reshape(4, 3, 2))
    out = tmp_path / "box.grdecl"
    box.to_file(out, fformat="grdecl")
    kw = read_grdecl(out)
    g = gcgrid.from_grdecl(kw["COORD"], kw["ZCORN"], kw.get("ACTNUM"), nx=4, ny=3)
    x = gcgrid.from_xtgeo(box, property=poro)
    np.testing.assert_allclose(g["corners"], x["corners"], rtol=0, atol=1e-3)
    assert x["values"] is not None and x["values"].shape == (2, 3, 4)
    assert x["values"][1, 2, 3] == poro.values[3, 2, 1]


def test_faulted_grid() -> None:
    throw = 7.5
    d = gc.data.faulted_grid(ni=40, nj=30, nk=20, throw=throw, seed=3)
    c, active, region, values = d["corners"], d["active"], d["region"], d["values"]
    assert c.shape == (20, 30, 40, 8, 3) and c.dtype == np.float64 and np.isfinite(c).all()
    assert active.shape == region.shape == values.shape == (20, 30, 40)
    assert active.dtype == bool and region.dtype == np.int32 and values.dtype == np.float64
    # Fault at i = 20: on the shared pillar the hanging wall's corners lie deeper by the throw
    # (0.6 x at the fault's ends, 1 x mid-way), where erosion did not clamp both sides.
    foot = c[:, :, 19][..., [1, 3, 5, 7], 2]
    hang = c[:, :, 20][..., [0, 2, 4, 6], 2]
    np.testing.assert_allclose(c[:, :, 19][..., [1, 3, 5, 7], :2], c[:, :, 20][..., [0, 2, 4, 6], :2])
    offset = foot - hang
    assert offset.max() == pytest.approx(throw, rel=1e-9)
    assert np.all(offset[10:] >= 0.6 * throw - 1e-9)  # below the erosion's reach
    # Pinch-out: layer 10 has cells with some collapsed corners (wedges) and fully collapsed ones,
    # which are inactive.
    layer = c[10]
    collapsed_corner = np.all(layer[:, :, :4] == layer[:, :, 4:], axis=-1)  # (nj, ni, 4)
    wedge = collapsed_corner.any(-1) & ~collapsed_corner.all(-1)
    assert wedge.any() and collapsed_corner.all(-1).any()
    assert not active[10][collapsed_corner.all(-1)].any()
    assert active[10][wedge].any()
    # Erosion: top layers truncated (collapsed) towards +y, intact towards -y.
    # (The footwall, i < 20, loses its top layers at the far edge; the hanging wall lies deeper.)
    assert not active[0, -1, :20].any() and active[:3, 0].mean() > 0.9
    assert active[3:10, -1, :20].mean() > 0.9
    assert len(np.unique(region)) >= 2
    assert np.isnan(values[~active]).all() and np.isfinite(values[active]).all()
    # Deterministic per seed.
    d2 = gc.data.faulted_grid(ni=40, nj=30, nk=20, throw=throw, seed=3)
    np.testing.assert_array_equal(d2["corners"], c)
