"""GRDECL files in, MAPAXES applied (issue 37): ``gc.grid.from_grdecl(..., mapaxes=)``,
``gc.grid.mapaxes_transform`` and ``gc.io.read_grdecl``.

What is checked:
- MAPAXES (X1 Y1 X2 Y2 X3 Y3: a point on the local y axis, the origin, a point on the local x
  axis) maps local (x, y) to ``origin + x * ex + y * ey`` with unit vectors ex, ey: the identity
  MAPAXES changes nothing; a rotated, shifted one rotates and shifts every corner (whatever the
  points' distances from the origin); a y axis pointing south mirrors the grid; a skewed one is
  applied as the affine map; bad ones (size, NaN, a point on the origin, parallel axes, words) are
  InputErrors naming ``mapaxes``;
- read_grdecl of files written here: MAPAXES (rotated, mirrored, skewed), ``n*value`` repeats,
  ``--`` comments, ECHO / NOECHO, skipped keywords (GDORIENT, multi-record FAULTS), INCLUDE, a property from a second
  file; geocull's reader and xtgeo's give the same corners, active cells and property as
  ``from_grdecl`` of the arrays (and xtgeo's own transform); geocull's reader also takes data on
  the keyword's line, ``/`` glued to a number and Fortran exponents (1.0D+03), which xtgeo's does
  not, and unquoted unit words and ``NOECHO /``; GRIDUNIT 'MAP' means no transform; EQUALS is warned of;
- bad files are InputErrors naming ``path``, the file and the cause (truncated in ZCORN, a count
  other than SPECGRID's, a word for a number, defaulted ZCORN values, no COORD, a binary file, no
  such file, a degenerate MAPAXES), with either engine where xtgeo reads; an absent property names
  ``properties``;
- the Reek files (``../shared/data/reek``): ``reek_sim_grid.grdecl`` (with MAPAXES) and
  ``reek_sim_poro.grdecl`` give, with either engine, the corners of xtgeo's EGRID of the same grid
  within 1 mm, its active cells and xtgeo's porosity, in UTM beside the horizons (no far-apart
  warning).
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import geocull as gc
from geocull import grid as gcgrid
from test_grid_input import hand_grid  # 2 x 2 x 2 grid, corners computed by hand

REEK = Path(__file__).resolve().parent.parent.parent / "shared" / "data" / "reek"


def _has_xtgeo() -> bool:
    try:
        import xtgeo  # noqa: F401
    except ImportError:
        return False
    return True


ENGINES = ["geocull", pytest.param("xtgeo", marks=pytest.mark.skipif(not _has_xtgeo(), reason="no xtgeo"))]


def rot(deg: float) -> np.ndarray:
    t = math.radians(deg)
    return np.array([[math.cos(t), -math.sin(t)], [math.sin(t), math.cos(t)]])


def mapaxes_of(origin: tuple[float, float], ex: np.ndarray, ey: np.ndarray, lx: float = 1.0,
               ly: float = 1.0) -> np.ndarray:
    o = np.asarray(origin)
    return np.concatenate([o + ly * ey, o, o + lx * ex])


# ------------------------------------------------------------------------------------------ MAPAXES


def test_mapaxes_rotates_shifts_mirrors_and_skews() -> None:
    coord, zcorn, actnum, want = hand_grid()
    local = gcgrid.from_grdecl(coord, zcorn, actnum, nx=2, ny=2)
    same = gcgrid.from_grdecl(coord, zcorn, actnum, nx=2, ny=2, mapaxes=[0, 1, 0, 0, 1, 0])
    np.testing.assert_array_equal(same["corners"], local["corners"])
    o = (456_510.625, 5_926_880.172)
    r = rot(30.0)
    for lx, ly in ((1.0, 1.0), (12_000.0, 7.5)):  # the points' distances do not matter
        g = gcgrid.from_grdecl(coord, zcorn, actnum, nx=2, ny=2, mapaxes=mapaxes_of(o, r[:, 0], r[:, 1], lx, ly))
        xy = want[..., :2] @ r.T + o
        np.testing.assert_allclose(g["corners"][..., :2], xy, rtol=0, atol=1e-6)
        np.testing.assert_array_equal(g["corners"][..., 2], want[..., 2])
        np.testing.assert_array_equal(g["active"], local["active"])
    # y axis pointing south: mirrored in y
    g = gcgrid.from_grdecl(coord, zcorn, nx=2, ny=2, mapaxes=(o[0], o[1] - 50.0, *o, o[0] + 3.0, o[1]))
    np.testing.assert_allclose(g["corners"][..., 0], o[0] + want[..., 0], atol=1e-6)
    np.testing.assert_allclose(g["corners"][..., 1], o[1] - want[..., 1], atol=1e-6)
    # skewed axes: the affine map of the unit vectors
    ex, ey = np.array([1.0, 0.0]), np.array([1.0, 1.0]) / math.sqrt(2.0)
    g = gcgrid.from_grdecl(coord, zcorn, nx=2, ny=2, mapaxes=mapaxes_of(o, ex, ey, 4.0, 9.0).reshape(3, 2))
    xy = o + want[..., :1] * ex + want[..., 1:2] * ey
    np.testing.assert_allclose(g["corners"][..., :2], xy, rtol=0, atol=1e-6)
    origin, ux, uy = gcgrid.mapaxes_transform(mapaxes_of(o, ex, ey, 4.0, 9.0))
    np.testing.assert_allclose(origin, o)
    np.testing.assert_allclose(ux, ex)
    np.testing.assert_allclose(uy, ey)


@pytest.mark.parametrize(("mapaxes", "why"), [
    ([0, 1, 0, 0, 1], "5 values"),
    (np.zeros((2, 4)), "8 values"),
    ([0, 1, 0, 0, 1, float("nan")], "non-finite"),
    ([0, 1, 5, 5, 5, 5], "x axis is the origin"),
    ([5, 5, 5, 5, 9, 5], "y axis is the origin"),
    ([2, 0, 0, 0, 1, 0], "parallel"),
    ([-3, 0.0000001, 0, 0, 7, 0], "parallel"),  # opposite directions
    (["a", "b", "c", "d", "e", "f"], "not 6 numbers"),
])
def test_bad_mapaxes(mapaxes: object, why: str) -> None:
    coord, zcorn, actnum, _ = hand_grid()
    with pytest.raises(gc.InputError, match=f"^mapaxes: .*{why}"):
        gcgrid.from_grdecl(coord, zcorn, actnum, nx=2, ny=2, mapaxes=mapaxes)


# ------------------------------------------------------------------------------------------- files


def block(name: str, values: np.ndarray, fmt: str, repeats: bool = False) -> str:
    """A keyword with 6 values a line; ``repeats``: runs of equal values written as n*value."""
    items: list[str] = []
    v = list(values)
    i = 0
    while i < len(v):
        j = i
        while repeats and j + 1 < len(v) and v[j + 1] == v[i]:
            j += 1
        items.append(f"{j - i + 1}*{fmt % v[i]}" if j > i else fmt % v[i])
        i = j + 1
    body = "\n".join(" ".join(items[n : n + 6]) for n in range(0, len(items), 6))
    return f"{name}\n{body}\n/\n"


MAPAXES = mapaxes_of((456_510.625, 5_926_880.172), rot(-20.0)[:, 0], rot(-20.0)[:, 1] * -1.0, 800.0, 300.0)


def write_deck(path: Path, mapaxes: np.ndarray | None = MAPAXES, gridunit: str = "'METRES  ' '        '",
               extra: str = "", zfmt: str = "%.6f") -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A GRDECL file of hand_grid() in every form the reader must accept; returns COORD, ZCORN,
    ACTNUM and PORO as written."""
    coord, zcorn, actnum, _ = hand_grid()
    poro = np.array([0.1, 0.1, 0.1, 0.25, 0.3, 0.0, 0.3, 0.3])
    head = "ECHO\n-- written by geocull's tests\nNOECHO\n\nMAPUNITS\n 'METRES  ' /\n"
    if mapaxes is not None:
        head += "MAPAXES\n" + " ".join(f"{v:.3f}" for v in mapaxes) + " / -- y point, origin, x point\n"
    head += f"GRIDUNIT\n{gridunit} /\n\nSPECGRID\n 2 2 2 1 F /\nGDORIENT\nINC INC INC DOWN RIGHT /\n"
    faults = "FAULTS\n'F1' 2 2 1 2 1 2 'X' /\n'F1' 2 2 1 2 1 2 'X' /\n/\n"
    zc = block("ZCORN", zcorn, zfmt, repeats=True)
    path.write_text(head + block("COORD", coord, "%.6f") + faults + zc + extra
                    + block("ACTNUM", actnum, "%d", repeats=True) + "EDIT\n")
    (path.parent / "poro.grdecl").write_text("-- a property file\n" + block("PORO", poro, "%.4f", repeats=True))
    return coord, zcorn, actnum, poro


@pytest.mark.parametrize("engine", ENGINES)
def test_read_grdecl_with_mapaxes(tmp_path: Path, engine: str) -> None:
    path = tmp_path / "grid.grdecl"
    coord, zcorn, actnum, poro = write_deck(path)
    text = path.read_text()
    assert "6*1" in text and "MAPAXES" in text  # repeats written
    kw = gc.io.read_grdecl([path, tmp_path / "poro.grdecl"], properties="PORO", engine=engine)  # type: ignore[arg-type]
    ref = gcgrid.from_grdecl(coord, zcorn, actnum, nx=2, ny=2, mapaxes=np.round(MAPAXES, 3))
    np.testing.assert_allclose(kw["corners"], ref["corners"], rtol=0, atol=2e-3)
    np.testing.assert_array_equal(kw["active"], ref["active"])
    assert kw["values"] is not None and kw["values"].shape == (2, 2, 2)
    want = poro.reshape(2, 2, 2).copy()
    want[~ref["active"]] = np.nan
    np.testing.assert_allclose(kw["values"], want, rtol=0, atol=1e-6)
    # world coordinates: near the MAPAXES origin, not at the local (0..25, 0..25)
    assert np.abs(kw["corners"][..., 0] - 456_510.0).max() < 100.0
    assert np.abs(kw["corners"][..., 1] - 5_926_880.0).max() < 100.0
    no_values = gc.io.read_grdecl(path, engine=engine)  # type: ignore[arg-type]
    assert no_values["values"] is None
    s = gc.Scene()
    s.add_grid(**kw, name="grid")  # the dict is add_grid's keyword arguments


@pytest.mark.skipif(not _has_xtgeo(), reason="no xtgeo")
def test_mapaxes_as_xtgeo_applies_it(tmp_path: Path) -> None:
    """Skewed and mirrored MAPAXES: geocull's reader, xtgeo's reader and xtgeo's own transform agree."""
    from xtgeo.grid3d._ecl_grid import MapAxes, transform_xtgeo_coord_by_mapaxes

    coord, zcorn, actnum, _ = hand_grid()
    for m in (MAPAXES, np.array([100.0, 300.0, 100.0, 200.0, 150.0, 250.0]), np.array([0.0, -1, 0, 0, 1, 0])):
        path = tmp_path / "m.grdecl"
        write_deck(path, m)
        mine = gc.io.read_grdecl(path, engine="geocull")
        theirs = gc.io.read_grdecl(path, engine="xtgeo")
        np.testing.assert_allclose(mine["corners"], theirs["corners"], rtol=0, atol=2e-3)
        xc = coord.reshape(3, 3, 6).swapaxes(0, 1).copy()  # xtgeo's coord layout (ni+1, nj+1, 6)
        xc = transform_xtgeo_coord_by_mapaxes(MapAxes.from_grdecl(list(np.round(m, 3))), xc)
        ref = gcgrid.from_grdecl(xc.swapaxes(0, 1).reshape(-1), zcorn, actnum, nx=2, ny=2)
        np.testing.assert_allclose(mine["corners"], ref["corners"], rtol=0, atol=2e-3)


def test_grdecl_reader_details(tmp_path: Path) -> None:
    coord, zcorn, actnum, _ = hand_grid()
    path = tmp_path / "grid.grdecl"
    write_deck(path, gridunit="'METRES' 'MAP'")  # COORD relative to the map already: no transform
    kw = gc.io.read_grdecl(path, engine="geocull")
    np.testing.assert_allclose(kw["corners"], gcgrid.from_grdecl(coord, zcorn, actnum, nx=2, ny=2)["corners"],
                               atol=1e-9)
    up = gc.io.read_grdecl(path, engine="geocull", z_positive="up")
    np.testing.assert_array_equal(up["corners"][..., 2], -kw["corners"][..., 2])
    # data on the keyword's line, "/" glued to the last value, Fortran exponents (xtgeo's reader
    # refuses these three), unquoted words, a stray "/" after a keyword without data
    text = path.read_text().replace("SPECGRID\n 2 2 2 1 F /", "SPECGRID 2 2 2 1 F/")
    text = text.replace("1000.000000", "1.000000D+03").replace("MAPUNITS\n 'METRES  ' /", "MAPUNITS\n METRES /")
    text = text.replace("NOECHO\n", "NOECHO /\n")
    assert "D+03" in text and "METRES /" in text and "NOECHO /" in text
    (tmp_path / "glued.grdecl").write_text(text.replace("\n/\nACTNUM", "/\nACTNUM"))
    glued = gc.io.read_grdecl(tmp_path / "glued.grdecl", engine="geocull")
    np.testing.assert_array_equal(glued["corners"], kw["corners"])
    # INCLUDE: the deck split over files, the grid's arrays in an included one
    inc = tmp_path / "inc"
    inc.mkdir()
    (inc / "arrays.inc").write_text(block("COORD", coord, "%.6f") + block("ZCORN", zcorn, "%.6f"))
    (tmp_path / "main.grdecl").write_text("SPECGRID\n2 2 2 1 F /\nINCLUDE\n 'inc/arrays.inc' /\n"
                                          + block("ACTNUM", actnum, "%d") + "PORO\n 8*0.2 /\n")
    kw = gc.io.read_grdecl(tmp_path / "main.grdecl", properties="poro", engine="geocull")
    np.testing.assert_allclose(kw["corners"], gcgrid.from_grdecl(coord, zcorn, actnum, nx=2, ny=2)["corners"],
                               atol=1e-9)
    assert kw["values"] is not None and np.nanmax(kw["values"]) == pytest.approx(0.2)
    assert np.isnan(kw["values"]).sum() == 1  # the inactive cell
    # EQUALS is not applied: warned of
    write_deck(path, extra="EQUALS\n 'PORO' 0.3 /\n/\n")
    with pytest.warns(gc.GeocullWarning, match="EQUALS"):
        gc.io.read_grdecl(path, engine="geocull")
    # an INCLUDE loop
    (tmp_path / "loop.grdecl").write_text("INCLUDE\n'loop.grdecl' /\n")
    with pytest.raises(gc.InputError, match="^path: .*INCLUDE nested"):
        gc.io.read_grdecl(tmp_path / "loop.grdecl", engine="geocull")


def _truncated(path: Path) -> None:
    text = path.read_text()
    path.write_text(text[: text.index("ZCORN") + 200])


def _wrong_count(path: Path) -> None:
    path.write_text(path.read_text().replace(" 2 2 2 1 F /", " 3 2 2 1 F /"))


def _word(path: Path) -> None:
    text = path.read_text()
    i = text.index("ZCORN") + 40
    path.write_text(text[:i] + " 10O5.0 " + text[i:])


def _defaulted(path: Path) -> None:
    text = path.read_text()
    i = text.index("ZCORN") + 6
    path.write_text(text[:i] + "2* " + text[i:])


def _no_coord(path: Path) -> None:
    text = path.read_text()
    path.write_text(text[: text.index("COORD")] + text[text.index("FAULTS"):])


def _degenerate_mapaxes(path: Path) -> None:
    write_deck(path, mapaxes=np.array([10.0, 10.0, 10.0, 10.0, 20.0, 10.0]))


def _binary(path: Path) -> None:
    path.write_bytes(b"\x00\x00\x00\x10SPECGRID" + bytes(range(256)) * 4)


@pytest.mark.parametrize(("damage", "cause"), [
    (_truncated, "ZCORN .*no '/' terminator"),
    (_wrong_count, "COORD .*54 values, expected 72"),
    (_word, "ZCORN .*'10O5.0' is not a number"),
    (_defaulted, "ZCORN .*'2\\*' defaults 2 values"),
    (_no_coord, "no COORD keyword"),
    (_degenerate_mapaxes, "MAPAXES .*mapaxes: the point on the y axis is the origin"),
    (_binary, "not GRDECL text"),
], ids=lambda x: getattr(x, "__name__", "")[1:] if callable(x) else "")
@pytest.mark.parametrize("engine", ENGINES)
def test_bad_files_are_input_errors_naming_path(tmp_path: Path, damage, cause: str, engine: str) -> None:
    path = tmp_path / "grid.grdecl"
    write_deck(path)
    damage(path)
    with pytest.raises(gc.InputError, match="^path: ") as e, warnings.catch_warnings():
        warnings.simplefilter("ignore")  # xtgeo's own warnings about what it reads
        gc.io.read_grdecl(path, engine=engine)  # type: ignore[arg-type]
    assert str(path) in str(e.value)
    if engine == "geocull":
        assert e.match(cause)


def test_bad_arguments(tmp_path: Path) -> None:
    path = tmp_path / "grid.grdecl"
    write_deck(path)
    with pytest.raises(gc.InputError, match="^path: no such file"):
        gc.io.read_grdecl(tmp_path / "nope.grdecl")
    with pytest.raises(gc.InputError, match="^path: .*neither a path"):
        gc.io.read_grdecl([])
    with pytest.raises(gc.InputError, match="^properties: no keyword PERMX"):
        gc.io.read_grdecl(path, properties="PERMX", engine="geocull")
    if _has_xtgeo():
        with pytest.raises(gc.InputError, match="^properties: "):
            gc.io.read_grdecl(path, properties="PERMX", engine="xtgeo")
    with pytest.raises(gc.InputError, match="^properties: "):
        gc.io.read_grdecl(path, properties=["PORO"])  # type: ignore[arg-type]
    with pytest.raises(gc.InputError, match="^engine: "):
        gc.io.read_grdecl(path, engine="resdata")  # type: ignore[arg-type]
    with pytest.raises(gc.InputError, match="^z_positive: "):
        gc.io.read_grdecl(path, z_positive="Down")  # type: ignore[arg-type]


# ------------------------------------------------------------------------------------------- Reek


@pytest.mark.skipif(not REEK.is_dir(), reason="../shared/data/reek not present")
@pytest.mark.parametrize("engine", ENGINES)
def test_reek_grdecl_lands_on_the_egrid(engine: str) -> None:
    xtgeo = pytest.importorskip("xtgeo")
    files = [REEK / "grid" / "reek_sim_grid.grdecl", REEK / "grid" / "reek_sim_poro.grdecl"]
    assert "MAPAXES" in files[0].read_text()[:2000]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # xtgeo's own deprecations
        kw = gc.io.read_grdecl(files, properties="PORO", engine=engine)  # type: ignore[arg-type]
        egrid = xtgeo.grid_from_file(REEK / "grid" / "REEK.EGRID")
        poro = xtgeo.gridproperty_from_file(files[1], fformat="grdecl", name="PORO", grid=egrid)
    ref = gc.io.from_xtgeo_grid(egrid, values=poro)
    assert kw["corners"].shape == (14, 64, 40, 8, 3)
    np.testing.assert_allclose(kw["corners"], ref["corners"], rtol=0, atol=1e-3)  # EGRID holds float32
    np.testing.assert_array_equal(kw["active"], ref["active"])
    assert ref["values"] is not None and kw["values"] is not None
    np.testing.assert_allclose(kw["values"], ref["values"], rtol=1e-6, equal_nan=True)
    # in UTM beside the horizons: no far-apart warning
    top = xtgeo.surface_from_file(REEK / "surfaces" / "topreek_rota.gri")
    s = gc.Scene()
    with warnings.catch_warnings():
        warnings.simplefilter("error", gc.GeocullWarning)
        s.add_heightfield(top, tiles=(2, 2))
        s.add_grid(**kw, name="Reek")
